#pragma once

/// glTF 2.0 loading into CPU-side Model data (tinygltf stays inside the .cpp). Upload to the
/// GPU is the renderer's separate step. Format: https://registry.khronos.org/glTF/specs/2.0/

#include <cstddef>
#include <filesystem>
#include <vector>

#include <glm/glm.hpp>

#include "scene_viewer/assets/model.hpp"

namespace scene_viewer {

/// Loads a .glb, or a .gltf with external .bin/images or data: URIs, into a Model whose
/// primitives are in the model frame: node transforms of the default scene are baked into
/// positions and normals (node_transform stays identity), normals are computed when missing,
/// non-indexed primitives get indices, base colour factor and texture are kept (texture decoded
/// to RGBA8). Only TRIANGLES primitives are drawn; others are skipped with a Model::warnings
/// entry. URIs that leave the file's folder (`..`, absolute paths, any scheme but data:) are
/// refused before anything is read. Throws std::runtime_error "<file>: <reason>"; nothing
/// half-built escapes.
Model load_model(const std::filesystem::path& path);

/// load_model() on the bytes of a .gltf or .glb already in memory: `path` is the file they stand
/// for (named in errors; relative URIs are looked up in its folder, under the same rules).
/// load_model() reads the file with the bounded reader and calls the same parser.
Model load_model_memory(const std::vector<unsigned char>& bytes, const std::filesystem::path& path);

/// A unit cube centred on the origin ([-0.5, 0.5] on each axis) with outward face normals and
/// one primitive of the given linear RGBA base colour: the stand-in for classes without a model.
Model make_box_model(const glm::vec4& colour);

/// Number of triangles over all primitives.
std::size_t triangle_count(const Model& model);

/// Recomputes Model::bounds_min/bounds_max from the primitives (positions transformed by each
/// primitive's node_transform); throws std::invalid_argument when the model has no vertex.
void update_bounds(Model& model);

/// Smooth vertex normals: the area-weighted sum of the adjacent triangles' normals, normalised
/// (vertices without area get +Y).
void compute_normals(MeshPrimitive& primitive);

}  // namespace scene_viewer
