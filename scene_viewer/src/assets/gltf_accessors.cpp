#include <cmath>
#include <cstring>
#include <string>

#include <glm/gtc/matrix_transform.hpp>
#include <glm/gtc/quaternion.hpp>

#include "gltf_internal.hpp"

namespace scene_viewer::gltf_detail {

namespace {

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

}  // namespace

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
    // Overflow-checked: every term comes from the file.
    std::uint64_t view_end = 0;
    std::uint64_t start = 0;
    std::uint64_t span = 0;
    std::uint64_t last = 0;
    const bool wraps =
        __builtin_add_overflow(std::uint64_t{bv.byteOffset}, std::uint64_t{bv.byteLength},
                               &view_end) ||
        __builtin_add_overflow(std::uint64_t{bv.byteOffset}, std::uint64_t{accessor.byteOffset},
                               &start) ||
        __builtin_mul_overflow(std::uint64_t{view.stride}, std::uint64_t{view.count - 1}, &span) ||
        __builtin_add_overflow(start, span, &last) ||
        __builtin_add_overflow(last, std::uint64_t{element}, &last);
    if (wraps || view_end > buffer.size() || last > view_end) {
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

namespace {

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

}  // namespace

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

int append_buffer_view(tinygltf::Model& gltf, const void* data, std::size_t size, int target) {
    std::vector<unsigned char>& bin = gltf.buffers[0].data;
    bin.resize((bin.size() + 3u) & ~std::size_t{3u}, 0);  // 4-byte alignment
    tinygltf::BufferView view;
    view.buffer = 0;
    view.byteOffset = bin.size();
    view.byteLength = size;
    view.target = target;
    const auto* bytes = static_cast<const unsigned char*>(data);
    bin.insert(bin.end(), bytes, bytes + size);
    gltf.bufferViews.push_back(view);
    return static_cast<int>(gltf.bufferViews.size()) - 1;
}

}  // namespace scene_viewer::gltf_detail
