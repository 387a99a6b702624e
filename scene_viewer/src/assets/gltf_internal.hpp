#pragma once

/// Internals of the glTF reader and writers shared by their files: reading a .gltf/.glb safely
/// into tinygltf's document (gltf_files.cpp), reading accessors, node transforms and texture
/// transforms out of it (gltf_accessors.cpp), and appending data to a document being written
/// (scene_export.cpp, web/cloud_glb.cpp). Private to the library.

#include <cstdint>
#include <filesystem>
#include <stdexcept>
#include <string>
#include <vector>

#include <tiny_gltf.h>
#include <glm/glm.hpp>
#include <nlohmann/json.hpp>

namespace scene_viewer::gltf_detail {

/// A reason without the file name; load_model() adds it.
class LoadError : public std::runtime_error {
  public:
    using std::runtime_error::runtime_error;
};

/// Reads a .gltf or .glb file into tinygltf's document: URIs that could leave the model's
/// folder are refused before parsing, file access is confined to that folder, images decode
/// through image_io, and required extensions are refused. Throws LoadError.
tinygltf::Model read_gltf(const std::filesystem::path& path);

/// read_gltf() on the file's bytes already in memory; `path` names the file (its folder is where
/// relative URIs are looked up). read_gltf() reads with the bounded reader and calls this.
tinygltf::Model read_gltf_memory(const std::vector<unsigned char>& bytes,
                                 const std::filesystem::path& path);

/// Checks a glTF document's JSON before tinygltf reads it: nesting within
/// scene_schema::kMaxJsonDepth, the node count within the model limit, sizes and offsets
/// non-negative integers up to 2^53 (so 64-bit sums cannot wrap), buffer views inside their
/// buffers' declared lengths, indices that exist, and URIs (check_uris). Throws LoadError
/// naming the JSON pointer.
void precheck_gltf_json(const std::string& json_text);

/// Refuses a buffer or image URI that could read outside the model's folder: any scheme but
/// data:, absolute paths, and relative paths whose `..` segments climb above the folder.
void check_uris(const nlohmann::json& doc);

/// Where an accessor's elements live, checked against its buffer.
struct AccessorView {
    const unsigned char* data = nullptr;  ///< first element, or null when all zeros
    std::size_t count = 0;
    std::size_t stride = 0;
    int components = 0;
    int component_type = 0;
    bool normalized = false;
};

/// Appends `size` bytes to buffer 0 at a 4-byte aligned offset and a buffer view over them
/// (`target` 0: none); returns the view's index.
int append_buffer_view(tinygltf::Model& gltf, const void* data, std::size_t size, int target);

AccessorView view_accessor(const tinygltf::Model& gltf, int index, const std::string& what);
int component_size(int component_type);
float read_component(const unsigned char* p, int component_type, bool normalized);

/// The N-component float vectors of an accessor (normalized integers converted); throws
/// LoadError when the accessor has another component count.
template <int N>
std::vector<glm::vec<N, float>> read_vectors(const tinygltf::Model& gltf, int index,
                                             const std::string& what) {
    const AccessorView view = view_accessor(gltf, index, what);
    if (view.components != N) {
        throw LoadError(what + ": expected " + std::to_string(N) + " components, got " +
                        std::to_string(view.components));
    }
    std::vector<glm::vec<N, float>> out(view.count, glm::vec<N, float>(0.0f));
    if (view.data == nullptr) {
        return out;
    }
    const std::size_t size = static_cast<std::size_t>(component_size(view.component_type));
    for (std::size_t i = 0; i < view.count; ++i) {
        const unsigned char* element = view.data + i * view.stride;
        for (int c = 0; c < N; ++c) {
            out[i][c] = read_component(element + static_cast<std::size_t>(c) * size,
                                       view.component_type, view.normalized);
        }
    }
    return out;
}

/// Unsigned integer indices of an accessor; throws LoadError for other types.
std::vector<std::uint32_t> read_indices(const tinygltf::Model& gltf, int index,
                                        const std::string& what);

/// The node's local matrix: its matrix, else translation * rotation * scale.
glm::mat4 local_transform(const tinygltf::Node& node);

/// GL name of a primitive mode, for error messages.
const char* mode_name(int mode);

/// KHR_texture_transform of a texture reference, as one affine UV matrix.
struct UvTransform {
    glm::mat3 matrix{1.0f};
    int tex_coord = 0;
};

UvTransform texture_transform(const tinygltf::TextureInfo& info);

}  // namespace scene_viewer::gltf_detail
