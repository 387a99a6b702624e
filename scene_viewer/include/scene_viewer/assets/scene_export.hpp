#pragma once

/// Export of an assembled scene as one self-contained binary glTF 2.0 file (.glb), so it opens
/// in Blender or any glTF viewer. tinygltf stays inside the .cpp.

#include <filesystem>
#include <string>
#include <vector>

#include <glm/glm.hpp>

#include "scene_viewer/assets/model.hpp"

namespace scene_viewer {

/// One model instance of the scene. The model is borrowed (it must outlive the export call);
/// instances of the same Model share one glTF mesh.
struct PlacedModel {
    const Model* model = nullptr;  ///< what to draw; must not be null
    glm::mat4 world{1.0f};         ///< model frame -> world, glTF/OpenGL frame (+Y up), metres
    std::string name;              ///< node name in the file (e.g. the entity id), may be empty
};

/// The scene as .glb bytes: one node per PlacedModel (its world matrix), one mesh per distinct
/// Model, one material per primitive (base colour factor and texture), textures embedded as PNG,
/// all buffers in the GLB's BIN chunk. Throws std::invalid_argument for a null model or a
/// non-finite matrix, std::runtime_error when serialisation fails.
std::vector<unsigned char> export_scene_glb_bytes(const std::vector<PlacedModel>& scene);

/// Writes export_scene_glb_bytes() to `path` atomically (temp file + rename); on failure no
/// file is left behind and std::runtime_error "<path>: <reason>" is thrown.
void export_scene_glb(const std::vector<PlacedModel>& scene, const std::filesystem::path& path);

}  // namespace scene_viewer
