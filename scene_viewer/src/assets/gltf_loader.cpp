#include "scene_viewer/assets/gltf_loader.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <fstream>
#include <limits>
#include <stdexcept>
#include <string>
#include <system_error>
#include <utility>
#include <vector>

#include <tiny_gltf.h>
#include <glm/gtc/matrix_transform.hpp>
#include <glm/gtc/quaternion.hpp>
#include <nlohmann/json.hpp>

#include "scene_viewer/assets/image_io.hpp"

namespace scene_viewer {
namespace {

namespace fs = std::filesystem;

/// A reason without the file name; load_model() adds it.
class LoadError : public std::runtime_error {
  public:
    using std::runtime_error::runtime_error;
};

std::vector<unsigned char> read_bytes(const fs::path& path) {
    std::error_code ec;
    if (!fs::is_regular_file(path, ec)) {
        throw LoadError(fs::exists(path, ec) ? "not a regular file" : "file not found");
    }
    std::vector<unsigned char> bytes;
    if (!read_file_bytes(path, bytes)) {
        throw LoadError("cannot read the file");
    }
    return bytes;
}

std::uint32_t read_u32_le(const unsigned char* p) {
    return static_cast<std::uint32_t>(p[0]) | (static_cast<std::uint32_t>(p[1]) << 8) |
           (static_cast<std::uint32_t>(p[2]) << 16) | (static_cast<std::uint32_t>(p[3]) << 24);
}

bool is_glb(const std::vector<unsigned char>& bytes) {
    return bytes.size() >= 4 && std::memcmp(bytes.data(), "glTF", 4) == 0;
}

/// The JSON chunk of a GLB container (glTF 2.0 spec, section "Binary glTF Layout"), with the
/// container's lengths checked so a truncated file is named as such.
std::string glb_json_chunk(const std::vector<unsigned char>& bytes) {
    if (bytes.size() < 20) {
        throw LoadError("truncated .glb: " + std::to_string(bytes.size()) +
                        " bytes, shorter than the 20-byte header");
    }
    const std::uint32_t version = read_u32_le(bytes.data() + 4);
    const std::uint32_t length = read_u32_le(bytes.data() + 8);
    if (version != 2) {
        throw LoadError("unsupported .glb container version " + std::to_string(version));
    }
    if (length > bytes.size()) {
        throw LoadError("truncated .glb: header says " + std::to_string(length) +
                        " bytes, file has " + std::to_string(bytes.size()));
    }
    const std::uint32_t chunk_length = read_u32_le(bytes.data() + 12);
    const std::uint32_t chunk_type = read_u32_le(bytes.data() + 16);
    if (chunk_type != 0x4E4F534Au) {
        throw LoadError("first .glb chunk is not JSON");
    }
    if (static_cast<std::uint64_t>(chunk_length) + 20u > length) {
        throw LoadError("truncated .glb: JSON chunk runs past the end of the file");
    }
    return std::string(reinterpret_cast<const char*>(bytes.data()) + 20, chunk_length);
}

std::string percent_decode(const std::string& in) {
    std::string out;
    out.reserve(in.size());
    auto hex = [](char c) -> int {
        if (c >= '0' && c <= '9') return c - '0';
        if (c >= 'a' && c <= 'f') return c - 'a' + 10;
        if (c >= 'A' && c <= 'F') return c - 'A' + 10;
        return -1;
    };
    for (std::size_t i = 0; i < in.size(); ++i) {
        if (in[i] == '%' && i + 2 < in.size() && hex(in[i + 1]) >= 0 && hex(in[i + 2]) >= 0) {
            out.push_back(static_cast<char>(hex(in[i + 1]) * 16 + hex(in[i + 2])));
            i += 2;
        } else {
            out.push_back(in[i]);
        }
    }
    return out;
}

/// Refuses a URI that could read outside the model's folder: any scheme but data:, absolute
/// paths, and relative paths whose `..` segments climb above the folder.
void check_uri(const std::string& uri, const std::string& pointer) {
    if (uri.rfind("data:", 0) == 0) {
        return;
    }
    std::string path = percent_decode(uri);
    std::replace(path.begin(), path.end(), '\\', '/');
    const std::size_t colon = path.find(':');
    if (colon != std::string::npos && path.find('/') > colon) {
        throw LoadError(pointer + ": URI \"" + uri +
                        "\" refused: only relative paths and data: URIs are allowed");
    }
    if (path.empty() || path.front() == '/') {
        throw LoadError(pointer + ": URI \"" + uri +
                        "\" refused: absolute paths leave the model's folder");
    }
    int depth = 0;
    std::size_t start = 0;
    while (start <= path.size()) {
        const std::size_t end = std::min(path.find('/', start), path.size());
        const std::string segment = path.substr(start, end - start);
        if (segment == "..") {
            if (--depth < 0) {
                throw LoadError(pointer + ": URI \"" + uri +
                                "\" refused: it leaves the model's folder");
            }
        } else if (!segment.empty() && segment != ".") {
            ++depth;
        }
        start = end + 1;
    }
}

void check_uris(const std::string& json_text) {
    const nlohmann::json doc = nlohmann::json::parse(json_text, nullptr, false);
    if (doc.is_discarded() || !doc.is_object()) {
        throw LoadError("not valid glTF JSON");
    }
    for (const char* key : {"buffers", "images"}) {
        const auto it = doc.find(key);
        if (it == doc.end() || !it->is_array()) {
            continue;
        }
        for (std::size_t i = 0; i < it->size(); ++i) {
            const nlohmann::json& item = (*it)[i];
            if (item.is_object() && item.contains("uri") && item["uri"].is_string()) {
                check_uri(item["uri"].get<std::string>(),
                          "/" + std::string(key) + "/" + std::to_string(i) + "/uri");
            }
        }
    }
}

/// File access for tinygltf, confined to the model's folder (second line of defence after
/// check_uris(): it also catches symbolic links that point elsewhere, and tinygltf's habit of
/// searching the working directory).
struct FolderGuard {
    fs::path root;                ///< canonical folder of the model file
    mutable std::string refused;  ///< the first existing file refused for being outside root

    bool inside(const std::string& path) const {
        std::error_code ec;
        const fs::path canonical = fs::weakly_canonical(fs::path(path), ec);
        if (ec) {
            return false;
        }
        auto r = root.begin();
        auto p = canonical.begin();
        for (; r != root.end(); ++r, ++p) {
            if (p == canonical.end() || *p != *r) {
                return false;
            }
        }
        return true;
    }
};

bool guard_file_exists(const std::string& path, void* user) {
    const auto* guard = static_cast<const FolderGuard*>(user);
    std::error_code ec;
    if (!fs::is_regular_file(path, ec)) return false;
    if (!guard->inside(path)) {
        if (guard->refused.empty()) guard->refused = path;
        return false;
    }
    return true;
}

std::string guard_expand(const std::string& path, void*) { return path; }

bool guard_read(std::vector<unsigned char>* out, std::string* err, const std::string& path,
                void* user) {
    const auto* guard = static_cast<const FolderGuard*>(user);
    if (!guard->inside(path)) {
        if (err != nullptr) *err += "refused: outside the model's folder";
        return false;
    }
    if (!read_file_bytes(path, *out)) {
        if (err != nullptr) *err += "cannot read " + path;
        return false;
    }
    return true;
}

bool guard_write(std::string* err, const std::string&, const std::vector<unsigned char>&, void*) {
    if (err != nullptr) *err += "writing is not allowed while loading";
    return false;
}

bool load_image(tinygltf::Image* image, const int index, std::string* err, std::string*, int, int,
                const unsigned char* bytes, int size, void*) {
    try {
        ImageRgba8 decoded = decode_image_memory(bytes, static_cast<std::size_t>(size),
                                                 "image " + std::to_string(index));
        image->width = decoded.width;
        image->height = decoded.height;
        image->component = 4;
        image->bits = 8;
        image->pixel_type = TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE;
        image->image = std::move(decoded.pixels);
        return true;
    } catch (const std::exception& e) {
        if (err != nullptr) *err += e.what();
        return false;
    }
}

int component_count(int type) {
    switch (type) {
        case TINYGLTF_TYPE_SCALAR:
            return 1;
        case TINYGLTF_TYPE_VEC2:
            return 2;
        case TINYGLTF_TYPE_VEC3:
            return 3;
        case TINYGLTF_TYPE_VEC4:
            return 4;
        default:
            return 0;
    }
}

int component_size(int component_type) {
    switch (component_type) {
        case TINYGLTF_COMPONENT_TYPE_BYTE:
        case TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE:
            return 1;
        case TINYGLTF_COMPONENT_TYPE_SHORT:
        case TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT:
            return 2;
        case TINYGLTF_COMPONENT_TYPE_UNSIGNED_INT:
        case TINYGLTF_COMPONENT_TYPE_FLOAT:
            return 4;
        default:
            return 0;
    }
}

/// Where an accessor's elements live, checked against its buffer.
struct AccessorView {
    const unsigned char* data = nullptr;  ///< first element, or null when all zeros
    std::size_t count = 0;
    std::size_t stride = 0;
    int components = 0;
    int component_type = 0;
    bool normalized = false;
};

AccessorView view_accessor(const tinygltf::Model& gltf, int index, const std::string& what) {
    if (index < 0 || static_cast<std::size_t>(index) >= gltf.accessors.size()) {
        throw LoadError(what + ": accessor " + std::to_string(index) + " does not exist");
    }
    const tinygltf::Accessor& accessor = gltf.accessors[static_cast<std::size_t>(index)];
    if (accessor.sparse.isSparse) {
        throw LoadError(what + ": sparse accessors are not supported");
    }
    // A guard against absurd counts (an accessor without a buffer view allocates its zeros).
    constexpr std::size_t kMaxElements = std::size_t{1} << 24;
    if (accessor.count > kMaxElements) {
        throw LoadError(what + ": accessor " + std::to_string(index) + " has " +
                        std::to_string(accessor.count) + " elements, more than " +
                        std::to_string(kMaxElements));
    }
    AccessorView view;
    view.count = accessor.count;
    view.components = component_count(accessor.type);
    view.component_type = accessor.componentType;
    view.normalized = accessor.normalized;
    const int size = component_size(accessor.componentType);
    if (view.components == 0 || size == 0) {
        throw LoadError(what + ": unsupported accessor type or component type");
    }
    const std::size_t element = static_cast<std::size_t>(size * view.components);
    view.stride = element;
    if (accessor.bufferView < 0 || view.count == 0) {
        return view;  // glTF: an accessor without a buffer view reads as zeros
    }
    if (static_cast<std::size_t>(accessor.bufferView) >= gltf.bufferViews.size()) {
        throw LoadError(what + ": buffer view " + std::to_string(accessor.bufferView) +
                        " does not exist");
    }
    const tinygltf::BufferView& bv =
        gltf.bufferViews[static_cast<std::size_t>(accessor.bufferView)];
    if (bv.buffer < 0 || static_cast<std::size_t>(bv.buffer) >= gltf.buffers.size()) {
        throw LoadError(what + ": buffer " + std::to_string(bv.buffer) + " does not exist");
    }
    const std::vector<unsigned char>& buffer =
        gltf.buffers[static_cast<std::size_t>(bv.buffer)].data;
    if (bv.byteStride != 0) {
        if (bv.byteStride < element) {
            throw LoadError(what + ": byteStride is smaller than one element");
        }
        view.stride = bv.byteStride;
    }
    const std::uint64_t view_end = static_cast<std::uint64_t>(bv.byteOffset) + bv.byteLength;
    const std::uint64_t last = static_cast<std::uint64_t>(bv.byteOffset) + accessor.byteOffset +
                               static_cast<std::uint64_t>(view.stride) * (view.count - 1) + element;
    if (view_end > buffer.size() || last > view_end) {
        throw LoadError(what + ": accessor " + std::to_string(index) +
                        " reads past the end of its buffer");
    }
    view.data = buffer.data() + bv.byteOffset + accessor.byteOffset;
    return view;
}

float read_component(const unsigned char* p, int component_type, bool normalized) {
    switch (component_type) {
        case TINYGLTF_COMPONENT_TYPE_FLOAT: {
            float v;
            std::memcpy(&v, p, 4);
            return v;
        }
        case TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE: {
            const float v = static_cast<float>(*p);
            return normalized ? v / 255.0f : v;
        }
        case TINYGLTF_COMPONENT_TYPE_BYTE: {
            std::int8_t s;
            std::memcpy(&s, p, 1);
            return normalized ? std::max(static_cast<float>(s) / 127.0f, -1.0f)
                              : static_cast<float>(s);
        }
        case TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT: {
            std::uint16_t u;
            std::memcpy(&u, p, 2);
            return normalized ? static_cast<float>(u) / 65535.0f : static_cast<float>(u);
        }
        case TINYGLTF_COMPONENT_TYPE_SHORT: {
            std::int16_t s;
            std::memcpy(&s, p, 2);
            return normalized ? std::max(static_cast<float>(s) / 32767.0f, -1.0f)
                              : static_cast<float>(s);
        }
        case TINYGLTF_COMPONENT_TYPE_UNSIGNED_INT: {
            std::uint32_t u;
            std::memcpy(&u, p, 4);
            return static_cast<float>(u);
        }
        default:
            return 0.0f;
    }
}

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

std::vector<std::uint32_t> read_indices(const tinygltf::Model& gltf, int index,
                                        const std::string& what) {
    const AccessorView view = view_accessor(gltf, index, what);
    if (view.components != 1 || view.component_type == TINYGLTF_COMPONENT_TYPE_FLOAT ||
        view.component_type == TINYGLTF_COMPONENT_TYPE_BYTE ||
        view.component_type == TINYGLTF_COMPONENT_TYPE_SHORT) {
        throw LoadError(what + ": indices must be unsigned byte, short or int scalars");
    }
    std::vector<std::uint32_t> out(view.count, 0u);
    if (view.data == nullptr) {
        return out;
    }
    for (std::size_t i = 0; i < view.count; ++i) {
        const unsigned char* p = view.data + i * view.stride;
        switch (view.component_type) {
            case TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE:
                out[i] = *p;
                break;
            case TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT: {
                std::uint16_t u;
                std::memcpy(&u, p, 2);
                out[i] = u;
                break;
            }
            default:
                std::memcpy(&out[i], p, 4);
                break;
        }
    }
    return out;
}

glm::mat4 local_transform(const tinygltf::Node& node) {
    if (node.matrix.size() == 16) {
        glm::mat4 m(1.0f);
        for (int i = 0; i < 16; ++i) {
            m[i / 4][i % 4] = static_cast<float>(node.matrix[static_cast<std::size_t>(i)]);
        }
        return m;
    }
    glm::mat4 m(1.0f);
    if (node.translation.size() == 3) {
        m = glm::translate(
            m, glm::vec3(node.translation[0], node.translation[1], node.translation[2]));
    }
    if (node.rotation.size() == 4) {
        const glm::quat q(
            static_cast<float>(node.rotation[3]), static_cast<float>(node.rotation[0]),
            static_cast<float>(node.rotation[1]), static_cast<float>(node.rotation[2]));
        m = m * glm::mat4_cast(q);
    }
    if (node.scale.size() == 3) {
        m = glm::scale(m, glm::vec3(node.scale[0], node.scale[1], node.scale[2]));
    }
    return m;
}

const char* mode_name(int mode) {
    switch (mode) {
        case TINYGLTF_MODE_POINTS:
            return "POINTS";
        case TINYGLTF_MODE_LINE:
            return "LINES";
        case TINYGLTF_MODE_LINE_LOOP:
            return "LINE_LOOP";
        case TINYGLTF_MODE_LINE_STRIP:
            return "LINE_STRIP";
        case TINYGLTF_MODE_TRIANGLE_STRIP:
            return "TRIANGLE_STRIP";
        case TINYGLTF_MODE_TRIANGLE_FAN:
            return "TRIANGLE_FAN";
        default:
            return "unknown";
    }
}

/// KHR_texture_transform of a texture reference, as one affine UV matrix.
struct UvTransform {
    glm::mat3 matrix{1.0f};
    int tex_coord = 0;
};

double number_or(const tinygltf::Value& object, const char* key, int index, double fallback) {
    if (!object.Has(key)) return fallback;
    const tinygltf::Value& v = object.Get(key);
    const tinygltf::Value& item =
        index < 0
            ? v
            : (v.IsArray() && v.ArrayLen() > static_cast<std::size_t>(index) ? v.Get(index)
                                                                             : tinygltf::Value());
    return item.IsNumber() || item.IsInt() ? item.GetNumberAsDouble() : fallback;
}

/// uv' = T(offset) * R(rotation) * S(scale) * uv, the matrix of the extension's specification
/// (KhronosGroup/glTF, extensions/2.0/Khronos/KHR_texture_transform/README.md).
UvTransform texture_transform(const tinygltf::TextureInfo& info) {
    UvTransform out;
    out.tex_coord = info.texCoord;
    const auto ext = info.extensions.find("KHR_texture_transform");
    if (ext == info.extensions.end() || !ext->second.IsObject()) return out;
    const tinygltf::Value& t = ext->second;
    const float ox = static_cast<float>(number_or(t, "offset", 0, 0.0));
    const float oy = static_cast<float>(number_or(t, "offset", 1, 0.0));
    const float r = static_cast<float>(number_or(t, "rotation", -1, 0.0));
    const float sx = static_cast<float>(number_or(t, "scale", 0, 1.0));
    const float sy = static_cast<float>(number_or(t, "scale", 1, 1.0));
    const glm::mat3 translation(1, 0, 0, 0, 1, 0, ox, oy, 1);
    const glm::mat3 rotation(std::cos(r), std::sin(r), 0, -std::sin(r), std::cos(r), 0, 0, 0, 1);
    const glm::mat3 scale(sx, 0, 0, 0, sy, 0, 0, 0, 1);
    out.matrix = translation * rotation * scale;
    out.tex_coord = static_cast<int>(number_or(t, "texCoord", -1, info.texCoord));
    return out;
}

/// Converts tinygltf's document into our Model: walks the scene's node forest, bakes transforms.
class Converter {
  public:
    Converter(const tinygltf::Model& gltf, Model& out) : gltf_(gltf), out_(out) {
        texture_slot_.assign(gltf.images.size(), -1);
        visited_.assign(gltf.nodes.size(), false);
    }

    void run() {
        std::vector<int> roots;
        int scene = gltf_.defaultScene;
        if (scene < 0 && !gltf_.scenes.empty()) scene = 0;
        if (scene >= static_cast<int>(gltf_.scenes.size())) {
            throw LoadError("default scene " + std::to_string(scene) + " does not exist");
        }
        if (scene >= 0) {
            roots = gltf_.scenes[static_cast<std::size_t>(scene)].nodes;
        } else {
            std::vector<bool> is_child(gltf_.nodes.size(), false);
            for (const tinygltf::Node& node : gltf_.nodes) {
                for (int child : node.children) {
                    if (child >= 0 && static_cast<std::size_t>(child) < is_child.size()) {
                        is_child[static_cast<std::size_t>(child)] = true;
                    }
                }
            }
            for (std::size_t i = 0; i < gltf_.nodes.size(); ++i) {
                if (!is_child[i]) roots.push_back(static_cast<int>(i));
            }
        }
        for (int root : roots) {
            visit(root, glm::mat4(1.0f));
        }
    }

  private:
    void visit(int index, const glm::mat4& parent) {
        if (index < 0 || static_cast<std::size_t>(index) >= gltf_.nodes.size()) {
            throw LoadError("node " + std::to_string(index) + " does not exist");
        }
        if (visited_[static_cast<std::size_t>(index)]) {
            throw LoadError("node " + std::to_string(index) +
                            " is reached twice: the node hierarchy is not a forest");
        }
        visited_[static_cast<std::size_t>(index)] = true;
        const tinygltf::Node& node = gltf_.nodes[static_cast<std::size_t>(index)];
        const glm::mat4 world = parent * local_transform(node);
        if (node.mesh >= 0) {
            if (static_cast<std::size_t>(node.mesh) >= gltf_.meshes.size()) {
                throw LoadError("node " + std::to_string(index) + ": mesh " +
                                std::to_string(node.mesh) + " does not exist");
            }
            add_mesh(node.mesh, world);
        }
        for (int child : node.children) {
            visit(child, world);
        }
    }

    void add_mesh(int mesh_index, const glm::mat4& world) {
        const tinygltf::Mesh& mesh = gltf_.meshes[static_cast<std::size_t>(mesh_index)];
        for (std::size_t p = 0; p < mesh.primitives.size(); ++p) {
            const tinygltf::Primitive& prim = mesh.primitives[p];
            const std::string what = "mesh " + std::to_string(mesh_index) + " (" + mesh.name +
                                     ") primitive " + std::to_string(p);
            if (prim.mode != TINYGLTF_MODE_TRIANGLES && prim.mode != -1) {
                out_.warnings.push_back(what + ": mode " + mode_name(prim.mode) +
                                        " skipped, only TRIANGLES are drawn");
                continue;
            }
            out_.primitives.push_back(convert_primitive(prim, world, what));
        }
    }

    MeshPrimitive convert_primitive(const tinygltf::Primitive& prim, const glm::mat4& world,
                                    const std::string& what) {
        MeshPrimitive out;
        const auto position = prim.attributes.find("POSITION");
        if (position == prim.attributes.end()) {
            throw LoadError(what + ": no POSITION attribute");
        }
        out.positions = read_vectors<3>(gltf_, position->second, what + " POSITION");
        const std::size_t n = out.positions.size();
        const auto normal = prim.attributes.find("NORMAL");
        if (normal != prim.attributes.end()) {
            out.normals = read_vectors<3>(gltf_, normal->second, what + " NORMAL");
            if (out.normals.size() != n) throw LoadError(what + ": NORMAL count differs");
        }
        const auto uv = prim.attributes.find("TEXCOORD_0");
        if (uv != prim.attributes.end()) {
            out.texcoords = read_vectors<2>(gltf_, uv->second, what + " TEXCOORD_0");
            if (out.texcoords.size() != n) throw LoadError(what + ": TEXCOORD_0 count differs");
        }
        if (prim.indices >= 0) {
            out.indices = read_indices(gltf_, prim.indices, what + " indices");
        } else {
            if (n > std::numeric_limits<std::uint32_t>::max()) {
                throw LoadError(what + ": too many vertices");
            }
            out.indices.resize(n);
            for (std::size_t i = 0; i < n; ++i) out.indices[i] = static_cast<std::uint32_t>(i);
        }
        if (out.indices.size() % 3 != 0) {
            throw LoadError(what + ": index count " + std::to_string(out.indices.size()) +
                            " is not a multiple of 3");
        }
        for (std::uint32_t i : out.indices) {
            if (i >= n) {
                throw LoadError(what + ": index " + std::to_string(i) + " out of range (" +
                                std::to_string(n) + " vertices)");
            }
        }
        // Bake the node transform; a mirroring transform flips the winding back to CCW.
        const glm::mat3 normal_matrix = glm::transpose(glm::inverse(glm::mat3(world)));
        for (glm::vec3& v : out.positions) v = glm::vec3(world * glm::vec4(v, 1.0f));
        for (glm::vec3& v : out.normals) {
            const glm::vec3 t = normal_matrix * v;
            const float len = glm::length(t);
            v = len > 0.0f ? t / len : glm::vec3(0.0f, 1.0f, 0.0f);
        }
        if (glm::determinant(glm::mat3(world)) < 0.0f) {
            for (std::size_t t = 0; t + 2 < out.indices.size(); t += 3) {
                std::swap(out.indices[t + 1], out.indices[t + 2]);
            }
        }
        if (out.normals.empty()) compute_normals(out);
        apply_material(prim.material, out, what);
        return out;
    }

    void apply_material(int material_index, MeshPrimitive& out, const std::string& what) {
        if (material_index < 0) return;
        if (static_cast<std::size_t>(material_index) >= gltf_.materials.size()) {
            throw LoadError(what + ": material " + std::to_string(material_index) +
                            " does not exist");
        }
        const tinygltf::Material& material =
            gltf_.materials[static_cast<std::size_t>(material_index)];
        out.material_name = material.name;
        const tinygltf::PbrMetallicRoughness& pbr = material.pbrMetallicRoughness;
        if (pbr.baseColorFactor.size() == 4) {
            out.base_colour = glm::vec4(pbr.baseColorFactor[0], pbr.baseColorFactor[1],
                                        pbr.baseColorFactor[2], pbr.baseColorFactor[3]);
        }
        const int texture = pbr.baseColorTexture.index;
        if (texture < 0) return;
        if (static_cast<std::size_t>(texture) >= gltf_.textures.size()) {
            throw LoadError(what + ": texture " + std::to_string(texture) + " does not exist");
        }
        const int source = gltf_.textures[static_cast<std::size_t>(texture)].source;
        if (source < 0 || static_cast<std::size_t>(source) >= gltf_.images.size()) {
            throw LoadError(what + ": texture " + std::to_string(texture) + " has no image");
        }
        const UvTransform uv_transform = texture_transform(pbr.baseColorTexture);
        if (uv_transform.tex_coord != 0) {
            out_.warnings.push_back(what + ": base colour texture uses TEXCOORD_" +
                                    std::to_string(uv_transform.tex_coord) +
                                    ", not loaded; drawn untextured");
            return;
        }
        int& slot = texture_slot_[static_cast<std::size_t>(source)];
        if (slot < 0) {
            const tinygltf::Image& image = gltf_.images[static_cast<std::size_t>(source)];
            if (image.image.empty() || image.component != 4 || image.bits != 8) {
                throw LoadError("image " + std::to_string(source) + " (" + image.uri +
                                ") could not be read");
            }
            ImageRgba8 decoded;
            decoded.width = image.width;
            decoded.height = image.height;
            decoded.pixels = image.image;
            slot = static_cast<int>(out_.textures.size());
            out_.textures.push_back(std::move(decoded));
        }
        out.texture = slot;
        if (out.texcoords.empty()) {
            out_.warnings.push_back(what + ": textured material without TEXCOORD_0");
            out.texcoords.assign(out.positions.size(), glm::vec2(0.0f));
        }
        if (uv_transform.matrix != glm::mat3(1.0f)) {
            for (glm::vec2& uv : out.texcoords)
                uv = glm::vec2(uv_transform.matrix * glm::vec3(uv, 1));
        }
    }

    const tinygltf::Model& gltf_;
    Model& out_;
    std::vector<int> texture_slot_;  ///< glTF image index -> Model::textures index
    std::vector<bool> visited_;
};

Model load_model_unchecked(const fs::path& path) {
    const std::vector<unsigned char> bytes = read_bytes(path);
    const bool binary = is_glb(bytes);
    check_uris(binary ? glb_json_chunk(bytes)
                      : std::string(reinterpret_cast<const char*>(bytes.data()), bytes.size()));
    if (bytes.size() > std::numeric_limits<unsigned int>::max()) {
        throw LoadError("file too large");
    }
    std::error_code ec;
    FolderGuard guard{fs::weakly_canonical(fs::absolute(path).parent_path(), ec), {}};
    if (ec) {
        throw LoadError("cannot resolve the model's folder: " + ec.message());
    }
    tinygltf::TinyGLTF loader;
    loader.SetFsCallbacks(tinygltf::FsCallbacks{&guard_file_exists, &guard_expand, &guard_read,
                                                &guard_write, &guard});
    loader.SetImageLoader(&load_image, nullptr);
    tinygltf::Model gltf;
    std::string err;
    std::string warn;
    const std::string base_dir = guard.root.string();
    const bool ok =
        binary ? loader.LoadBinaryFromMemory(&gltf, &err, &warn, bytes.data(),
                                             static_cast<unsigned int>(bytes.size()), base_dir)
               : loader.LoadASCIIFromString(&gltf, &err, &warn,
                                            reinterpret_cast<const char*>(bytes.data()),
                                            static_cast<unsigned int>(bytes.size()), base_dir);
    if (!guard.refused.empty()) {
        throw LoadError(guard.refused + " is outside the model's folder (refused)");
    }
    if (!ok) {
        std::string reason = err.empty() ? warn : err;
        while (!reason.empty() && (reason.back() == '\n' || reason.back() == ' '))
            reason.pop_back();
        std::replace(reason.begin(), reason.end(), '\n', ';');
        throw LoadError("tinygltf: " + (reason.empty() ? std::string("cannot parse") : reason));
    }
    for (const std::string& required : gltf.extensionsRequired) {
        throw LoadError("required extension " + required + " is not supported");
    }
    Model model;
    model.name = path.filename().string();
    Converter(gltf, model).run();
    if (triangle_count(model) == 0) {
        throw LoadError("no triangles in the default scene");
    }
    update_bounds(model);
    return model;
}

}  // namespace

Model load_model(const std::filesystem::path& path) {
    try {
        return load_model_unchecked(path);
    } catch (const std::exception& e) {
        throw std::runtime_error(path.string() + ": " + e.what());
    }
}

std::size_t triangle_count(const Model& model) {
    std::size_t count = 0;
    for (const MeshPrimitive& p : model.primitives) count += p.indices.size() / 3;
    return count;
}

void update_bounds(Model& model) {
    glm::vec3 lo(std::numeric_limits<float>::max());
    glm::vec3 hi(std::numeric_limits<float>::lowest());
    bool any = false;
    for (const MeshPrimitive& p : model.primitives) {
        for (const glm::vec3& v : p.positions) {
            const glm::vec3 w(p.node_transform * glm::vec4(v, 1.0f));
            lo = glm::min(lo, w);
            hi = glm::max(hi, w);
            any = true;
        }
    }
    if (!any) {
        throw std::invalid_argument("update_bounds: model " + model.name + " has no vertex");
    }
    model.bounds_min = lo;
    model.bounds_max = hi;
}

void compute_normals(MeshPrimitive& primitive) {
    std::vector<glm::vec3> sum(primitive.positions.size(), glm::vec3(0.0f));
    for (std::size_t t = 0; t + 2 < primitive.indices.size(); t += 3) {
        const std::uint32_t a = primitive.indices[t];
        const std::uint32_t b = primitive.indices[t + 1];
        const std::uint32_t c = primitive.indices[t + 2];
        // The cross product's length is twice the area: larger triangles weigh more.
        const glm::vec3 n = glm::cross(primitive.positions[b] - primitive.positions[a],
                                       primitive.positions[c] - primitive.positions[a]);
        sum[a] += n;
        sum[b] += n;
        sum[c] += n;
    }
    for (glm::vec3& n : sum) {
        const float len = glm::length(n);
        n = len > 0.0f ? n / len : glm::vec3(0.0f, 1.0f, 0.0f);
    }
    primitive.normals = std::move(sum);
}

Model make_box_model(const glm::vec4& colour) {
    struct Face {
        glm::vec3 normal;
        glm::vec3 u;
        glm::vec3 v;
    };
    // u x v == normal, so each face's quad (-u-v, +u-v, +u+v, -u+v) is counter-clockwise.
    const std::array<Face, 6> faces = {{
        {{1, 0, 0}, {0, 0, -1}, {0, 1, 0}},
        {{-1, 0, 0}, {0, 0, 1}, {0, 1, 0}},
        {{0, 1, 0}, {1, 0, 0}, {0, 0, -1}},
        {{0, -1, 0}, {1, 0, 0}, {0, 0, 1}},
        {{0, 0, 1}, {1, 0, 0}, {0, 1, 0}},
        {{0, 0, -1}, {-1, 0, 0}, {0, 1, 0}},
    }};
    MeshPrimitive box;
    box.base_colour = colour;
    for (const Face& f : faces) {
        const auto base = static_cast<std::uint32_t>(box.positions.size());
        const glm::vec3 c = 0.5f * f.normal;
        const std::array<glm::vec2, 4> corners = {{{-1, -1}, {1, -1}, {1, 1}, {-1, 1}}};
        for (const glm::vec2& k : corners) {
            box.positions.push_back(c + 0.5f * k.x * f.u + 0.5f * k.y * f.v);
            box.normals.push_back(f.normal);
        }
        for (std::uint32_t i : {0u, 1u, 2u, 0u, 2u, 3u}) box.indices.push_back(base + i);
    }
    Model model;
    model.name = "box";
    model.primitives.push_back(std::move(box));
    update_bounds(model);
    return model;
}

}  // namespace scene_viewer
