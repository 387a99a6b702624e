#include <algorithm>
#include <climits>
#include <cstdint>
#include <cstring>
#include <fstream>
#include <limits>
#include <string>
#include <system_error>
#include <vector>

#include <nlohmann/json.hpp>

#include "gltf_internal.hpp"
#include "scene_viewer/assets/image_io.hpp"
#include "stereoscene/support/atomic_file.hpp"
#include "stereoscene/support/file_read.hpp"
#include "stereoscene/support/limits.hpp"

namespace scene_viewer::gltf_detail {
namespace {

namespace fs = std::filesystem;

std::vector<unsigned char> read_bytes(const fs::path& path) {
    try {
        return stereoscene::support::read_binary_input(path);
    } catch (const stereoscene::support::FileError& e) {
        // FileError starts with the path, which load_model() adds again.
        std::string reason = e.what();
        const std::string prefix = path.string() + ": ";
        if (reason.rfind(prefix, 0) == 0) reason.erase(0, prefix.size());
        throw LoadError(reason);
    }
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
void check_one_uri(const std::string& uri, const std::string& pointer) {
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
    try {
        *out = stereoscene::support::read_binary_input(path);
    } catch (const std::exception& e) {
        if (err != nullptr) *err += e.what();
        return false;
    }
    return true;
}

bool guard_write(std::string* err, const std::string&, const std::vector<unsigned char>&, void*) {
    if (err != nullptr) *err += "writing is not allowed while loading";
    return false;
}

/// What the image callback needs to check an image before decoding it.
struct ImageContext {
    const tinygltf::Model* model = nullptr;  ///< the document being read (its buffers are in)
    std::uint64_t pixels = 0;                ///< pixels decoded so far, all images together
};

/// Whether an image held in a buffer view lies inside its buffer's bytes (tinygltf passes the
/// view's start and length unchecked; precheck_gltf_json() checked the declared lengths).
bool image_in_bounds(const ImageContext& context, const tinygltf::Image& image) {
    if (image.bufferView < 0) return true;
    const tinygltf::Model& model = *context.model;
    if (static_cast<std::size_t>(image.bufferView) >= model.bufferViews.size()) return false;
    const tinygltf::BufferView& view =
        model.bufferViews[static_cast<std::size_t>(image.bufferView)];
    if (view.buffer < 0 || static_cast<std::size_t>(view.buffer) >= model.buffers.size()) {
        return false;
    }
    const std::size_t size = model.buffers[static_cast<std::size_t>(view.buffer)].data.size();
    return view.byteOffset <= size && view.byteLength <= size - view.byteOffset &&
           view.byteLength <= static_cast<std::size_t>(INT_MAX);
}

bool load_image(tinygltf::Image* image, const int index, std::string* err, std::string*, int, int,
                const unsigned char* bytes, int size, void* user) {
    auto* context = static_cast<ImageContext*>(user);
    if (!image_in_bounds(*context, *image)) {
        if (err != nullptr) {
            *err += "image " + std::to_string(index) + ": its buffer view runs past its buffer";
        }
        return false;
    }
    try {
        const stereoscene::support::Limits& limits = stereoscene::support::limits();
        const std::uint64_t pixels = image_pixels(bytes, static_cast<std::size_t>(size));
        // (image_pixels throws for an unreadable header; the catch below names the image.)
        context->pixels += pixels;
        stereoscene::support::check_limit("images of the model", context->pixels,
                                          limits.max_image_pixels, "pixels",
                                          stereoscene::support::kPixelsHint);
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
        if (err != nullptr) *err += "image " + std::to_string(index) + ": " + e.what();
        return false;
    }
}

}  // namespace

void check_uris(const nlohmann::json& doc) {
    for (const char* key : {"buffers", "images"}) {
        const auto it = doc.find(key);
        if (it == doc.end() || !it->is_array()) {
            continue;
        }
        for (std::size_t i = 0; i < it->size(); ++i) {
            const nlohmann::json& item = (*it)[i];
            if (item.is_object() && item.contains("uri") && item["uri"].is_string()) {
                check_one_uri(item["uri"].get<std::string>(),
                              "/" + std::string(key) + "/" + std::to_string(i) + "/uri");
            }
        }
    }
}

tinygltf::Model read_gltf(const fs::path& path) { return read_gltf_memory(read_bytes(path), path); }

tinygltf::Model read_gltf_memory(const std::vector<unsigned char>& bytes, const fs::path& path) {
    const bool binary = is_glb(bytes);
    precheck_gltf_json(
        binary ? glb_json_chunk(bytes)
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
    tinygltf::Model gltf;
    ImageContext images{&gltf, 0};
    loader.SetImageLoader(&load_image, &images);
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
    return gltf;
}

}  // namespace scene_viewer::gltf_detail
