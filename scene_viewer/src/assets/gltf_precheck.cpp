#include <cstdint>
#include <string>

#include <nlohmann/json.hpp>

#include "gltf_internal.hpp"
#include "scene_schema/entities.hpp"
#include "scene_schema/json_text.hpp"
#include "stereoscene/support/limits.hpp"

namespace scene_viewer::gltf_detail {
namespace {

using nlohmann::json;

/// Largest size or offset accepted in a glTF document: 2^53, the largest integer a JSON number
/// holds exactly. Sums of two such numbers cannot overflow 64 bits.
constexpr std::uint64_t kMaxGltfInteger = std::uint64_t{1} << 53;

const json* array_member(const json& doc, const char* key) {
    const auto it = doc.find(key);
    return it != doc.end() && it->is_array() ? &*it : nullptr;
}

/// The unsigned integer at `object[key]` (`fallback` when absent); refuses negatives, fractions,
/// and values above kMaxGltfInteger, which later 64-bit offset sums could overflow.
std::uint64_t size_member(const json& object, const char* key, const std::string& pointer,
                          std::uint64_t fallback) {
    const auto it = object.find(key);
    if (it == object.end()) return fallback;
    const std::string where = pointer + "/" + key;
    if (it->is_number_unsigned()) {
        const std::uint64_t v = it->get<std::uint64_t>();
        if (v > kMaxGltfInteger) throw LoadError(where + ": " + std::to_string(v) + " too large");
        return v;
    }
    if (it->is_number_integer()) throw LoadError(where + ": negative");
    throw LoadError(where + ": not a non-negative integer");
}

/// The index at `object[key]` into an array of `count` items, or -1 when absent.
std::int64_t index_member(const json& object, const char* key, const std::string& pointer,
                          std::size_t count) {
    if (!object.contains(key)) return -1;
    const std::uint64_t v = size_member(object, key, pointer, 0);
    if (v >= count) {
        throw LoadError(pointer + "/" + key + ": " + std::to_string(v) + " does not exist");
    }
    return static_cast<std::int64_t>(v);
}

std::size_t array_size(const json& doc, const char* key) {
    const json* a = array_member(doc, key);
    return a == nullptr ? 0 : a->size();
}

/// Checks the sizes and offsets of buffers, buffer views and accessors, and that an image held
/// in a buffer view lies inside its buffer's declared length (tinygltf hands such images to the
/// decoder unchecked).
void check_layout(const json& doc) {
    const std::size_t buffer_count = array_size(doc, "buffers");
    std::vector<std::uint64_t> buffer_length(buffer_count, 0);
    for (std::size_t i = 0; i < buffer_count; ++i) {
        const json& b = doc["buffers"][i];
        if (!b.is_object()) continue;
        buffer_length[i] = size_member(b, "byteLength", "/buffers/" + std::to_string(i), 0);
    }
    const std::size_t view_count = array_size(doc, "bufferViews");
    std::vector<std::int64_t> view_buffer(view_count, -1);
    std::vector<std::uint64_t> view_end(view_count, 0);
    for (std::size_t i = 0; i < view_count; ++i) {
        const json& v = doc["bufferViews"][i];
        if (!v.is_object()) continue;
        const std::string pointer = "/bufferViews/" + std::to_string(i);
        const std::uint64_t offset = size_member(v, "byteOffset", pointer, 0);
        const std::uint64_t length = size_member(v, "byteLength", pointer, 0);
        size_member(v, "byteStride", pointer, 0);
        view_buffer[i] = index_member(v, "buffer", pointer, buffer_count);
        view_end[i] = offset + length;
        if (view_buffer[i] >= 0 &&
            view_end[i] > buffer_length[static_cast<std::size_t>(view_buffer[i])]) {
            throw LoadError(pointer + ": byteOffset + byteLength " + std::to_string(view_end[i]) +
                            " runs past its buffer's byteLength");
        }
    }
    for (std::size_t i = 0; i < array_size(doc, "accessors"); ++i) {
        const json& a = doc["accessors"][i];
        if (!a.is_object()) continue;
        const std::string pointer = "/accessors/" + std::to_string(i);
        size_member(a, "byteOffset", pointer, 0);
        size_member(a, "count", pointer, 0);
        index_member(a, "bufferView", pointer, view_count);
    }
    for (std::size_t i = 0; i < array_size(doc, "images"); ++i) {
        const json& image = doc["images"][i];
        if (!image.is_object()) continue;
        const std::string pointer = "/images/" + std::to_string(i);
        const std::int64_t view = index_member(image, "bufferView", pointer, view_count);
        if (view >= 0 && view_buffer[static_cast<std::size_t>(view)] < 0) {
            throw LoadError(pointer + ": its buffer view has no buffer");
        }
    }
}

}  // namespace

void precheck_gltf_json(const std::string& json_text) {
    json doc;
    try {
        // The strict reader bounds the nesting, so tinygltf's recursive parser, which reads the
        // same text next, stays far from the stack's end.
        doc = scene_schema::parse_json(json_text);
    } catch (const scene_schema::SchemaError& e) {
        throw LoadError("not valid glTF JSON: " +
                        (e.pointer().empty() ? std::string() : e.pointer() + ": ") + e.rule());
    }
    if (!doc.is_object()) throw LoadError("not valid glTF JSON: not an object");
    stereoscene::support::check_limit("glTF nodes", array_size(doc, "nodes"),
                                      stereoscene::support::limits().max_model_vertices, "nodes",
                                      stereoscene::support::kVerticesHint);
    check_layout(doc);
    check_uris(doc);
}

}  // namespace scene_viewer::gltf_detail
