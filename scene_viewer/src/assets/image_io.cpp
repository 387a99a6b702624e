#include "scene_viewer/assets/image_io.hpp"

#include <climits>
#include <fstream>
#include <mutex>
#include <stdexcept>

#include <stb/stb_image.h>
#include <stb/stb_image_write.h>

namespace scene_viewer {
namespace {

/// Reads a whole file in one call, sized by seeking to its end.
bool slurp(const std::filesystem::path& path, std::vector<unsigned char>& out) {
    std::ifstream in(path, std::ios::binary | std::ios::ate);
    if (!in) return false;
    const std::streamoff size = in.tellg();
    if (size < 0) return false;
    out.resize(static_cast<std::size_t>(size));
    in.seekg(0);
    return size == 0 || static_cast<bool>(in.read(reinterpret_cast<char*>(out.data()), size));
}

void append_bytes(void* context, void* data, int size) {
    auto* out = static_cast<std::vector<unsigned char>*>(context);
    const auto* bytes = static_cast<const unsigned char*>(data);
    out->insert(out->end(), bytes, bytes + size);
}

}  // namespace

std::vector<unsigned char> encode_png(const ImageRgba8& image, int zlib_level) {
    if (image.width <= 0 || image.height <= 0) {
        throw std::invalid_argument("encode_png: image is empty (" + std::to_string(image.width) +
                                    "x" + std::to_string(image.height) + ")");
    }
    if (image.pixels.size() !=
        static_cast<std::size_t>(image.width) * static_cast<std::size_t>(image.height) * 4u) {
        throw std::invalid_argument("encode_png: pixels holds " +
                                    std::to_string(image.pixels.size()) + " bytes, expected " +
                                    "width * height * 4");
    }
    if (image.width > INT_MAX / 4) {
        throw std::invalid_argument("encode_png: width too large");
    }
    if (zlib_level < 0 || zlib_level > 9) {
        throw std::invalid_argument("encode_png: zlib_level must be 0..9");
    }
    // stb keeps the level in a global; serialise encoders so concurrent calls stay correct.
    static std::mutex level_mutex;
    std::lock_guard<std::mutex> lock(level_mutex);
    stbi_write_png_compression_level = zlib_level;
    std::vector<unsigned char> out;
    const int ok = stbi_write_png_to_func(append_bytes, &out, image.width, image.height, 4,
                                          image.pixels.data(), image.width * 4);
    if (ok == 0) {
        throw std::runtime_error("encode_png: stb_image_write failed");
    }
    return out;
}

ImageRgba8 decode_image_memory(const unsigned char* bytes, std::size_t size,
                               const std::string& what) {
    if (size == 0 || size > static_cast<std::size_t>(INT_MAX)) {
        throw std::runtime_error(what + ": image data is empty or too large");
    }
    int width = 0;
    int height = 0;
    int channels = 0;
    unsigned char* data =
        stbi_load_from_memory(bytes, static_cast<int>(size), &width, &height, &channels, 4);
    if (data == nullptr) {
        const char* reason = stbi_failure_reason();
        throw std::runtime_error(
            what + ": cannot decode image: " + (reason != nullptr ? reason : "unknown reason"));
    }
    ImageRgba8 image;
    image.width = width;
    image.height = height;
    image.pixels.assign(
        data, data + static_cast<std::size_t>(width) * static_cast<std::size_t>(height) * 4u);
    stbi_image_free(data);
    return image;
}

ImageRgba8 decode_image(const std::filesystem::path& path) {
    std::vector<unsigned char> bytes;
    if (!slurp(path, bytes)) {
        throw std::runtime_error(path.string() + ": cannot read image");
    }
    return decode_image_memory(bytes.data(), bytes.size(), path.string());
}

}  // namespace scene_viewer
