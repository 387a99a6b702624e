#pragma once

/// CPU-side model data, made by the asset loader and uploaded by the renderer as a separate
/// step. No GL and no tinygltf types here.

#include <cstdint>
#include <string>
#include <tuple>
#include <vector>

#include <glm/glm.hpp>

namespace scene_viewer {

/// Decoded RGBA8 image (base colour texture).
struct ImageRgba8 {
    int width = 0;
    int height = 0;
    std::vector<std::uint8_t> pixels;  ///< width * height * 4 bytes, rows top to bottom
};

/// What a glTF material says beyond the base colour. The renderer draws the base colour; the
/// .glb export writes these back so other viewers show third-party models as their authors
/// made them. The defaults are the project's own models' (matte, not metallic).
struct MaterialProperties {
    float metallic = 0.0f;              ///< metallicFactor
    float roughness = 0.8f;             ///< roughnessFactor
    bool double_sided = false;          ///< doubleSided: no back-face culling
    std::string alpha_mode = "OPAQUE";  ///< OPAQUE, MASK or BLEND
    float alpha_cutoff = 0.5f;          ///< MASK: alpha below this is discarded
    glm::vec3 emissive{0.0f};           ///< emissiveFactor
};

/// The sampler of a base colour texture (glTF sampler: GL filter and wrap enums; -1 = unset,
/// the viewer chooses).
struct TextureSampler {
    int mag_filter = -1;
    int min_filter = -1;
    int wrap_s = 10497;  ///< GL_REPEAT
    int wrap_t = 10497;
    bool operator<(const TextureSampler& o) const {
        return std::tie(mag_filter, min_filter, wrap_s, wrap_t) <
               std::tie(o.mag_filter, o.min_filter, o.wrap_s, o.wrap_t);
    }
};

/// One drawable primitive: triangles with one material, in the model's own frame.
struct MeshPrimitive {
    std::vector<glm::vec3> positions;
    std::vector<glm::vec3> normals;      ///< same count as positions (computed when missing)
    std::vector<glm::vec2> texcoords;    ///< empty or same count as positions
    std::vector<std::uint32_t> indices;  ///< triangle list
    glm::vec4 base_colour{1.0f};         ///< glTF baseColorFactor (linear RGBA)
    int texture = -1;                    ///< index into Model::textures, or -1
    glm::mat4 node_transform{1.0f};      ///< node hierarchy flattened into the model frame
    std::string material_name;           ///< glTF material name (may be empty), kept for export
    MaterialProperties material;         ///< the rest of the material, kept for export
    TextureSampler sampler;              ///< the base colour texture's sampler, kept for export
};

/// A whole model: every primitive of every node of the default scene, flattened.
struct Model {
    std::string name;  ///< file name or generated name
    std::vector<MeshPrimitive> primitives;
    std::vector<ImageRgba8> textures;
    glm::vec3 bounds_min{0.0f};  ///< axis-aligned bounds in the model frame
    glm::vec3 bounds_max{0.0f};
    std::vector<std::string>
        warnings;  ///< what the loader skipped and why (e.g. a LINES primitive)
};

}  // namespace scene_viewer
