#include "scene_viewer/assets/image_io.hpp"

#include <climits>
#include <cstring>
#include <stdexcept>

#include <stb/stb_image.h>

#include "stereoscene/support/file_read.hpp"
#include "stereoscene/support/limits.hpp"

#include <zlib.h>

namespace scene_viewer {
namespace {

void put_u32(std::vector<unsigned char>& out, std::uint32_t v) {
    for (int s = 24; s >= 0; s -= 8) out.push_back(static_cast<unsigned char>(v >> s));
}

void put_chunk(std::vector<unsigned char>& out, const char* type, const unsigned char* data,
               std::size_t size) {
    put_u32(out, static_cast<std::uint32_t>(size));
    const std::size_t start = out.size();
    out.insert(out.end(), type, type + 4);
    out.insert(out.end(), data, data + size);
    const uLong crc = crc32(0L, out.data() + start, static_cast<uInt>(out.size() - start));
    put_u32(out, static_cast<std::uint32_t>(crc));
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
    return encode_png_samples(image.pixels.data(), image.width, image.height, 8, 6, 4, zlib_level);
}

std::vector<unsigned char> encode_png_samples(const unsigned char* rows, int width, int height,
                                              int bit_depth, int colour_type, int bytes_per_pixel,
                                              int zlib_level) {
    if (width <= 0 || height <= 0 || bytes_per_pixel <= 0 || zlib_level < 0 || zlib_level > 9) {
        throw std::invalid_argument("encode_png_samples: bad size or zlib level");
    }
    const std::size_t row_bytes = static_cast<std::size_t>(width) * bytes_per_pixel;
    const std::size_t bpp = static_cast<std::size_t>(bytes_per_pixel);
    std::vector<unsigned char> filtered((row_bytes + 1) * static_cast<std::size_t>(height));
    for (std::size_t y = 0; y < static_cast<std::size_t>(height); ++y) {
        const unsigned char* row = rows + row_bytes * y;
        unsigned char* dst = filtered.data() + (row_bytes + 1) * y;
        dst[0] = 1;  // Sub: each byte minus the same byte of the pixel to its left
        for (std::size_t i = 0; i < bpp && i < row_bytes; ++i) dst[1 + i] = row[i];
        for (std::size_t i = bpp; i < row_bytes; ++i) {
            dst[1 + i] = static_cast<unsigned char>(row[i] - row[i - bpp]);
        }
    }
    uLongf size = compressBound(static_cast<uLong>(filtered.size()));
    std::vector<unsigned char> idat(size);
    if (compress2(idat.data(), &size, filtered.data(), static_cast<uLong>(filtered.size()),
                  zlib_level) != Z_OK) {
        throw std::runtime_error("encode_png: zlib compression failed");
    }
    std::vector<unsigned char> png = {0x89, 'P', 'N', 'G', '\r', '\n', 0x1a, '\n'};
    png.reserve(size + 64);
    std::vector<unsigned char> ihdr;
    put_u32(ihdr, static_cast<std::uint32_t>(width));
    put_u32(ihdr, static_cast<std::uint32_t>(height));
    ihdr.insert(ihdr.end(), {static_cast<unsigned char>(bit_depth),
                             static_cast<unsigned char>(colour_type), 0, 0, 0});
    put_chunk(png, "IHDR", ihdr.data(), ihdr.size());
    put_chunk(png, "IDAT", idat.data(), size);
    put_chunk(png, "IEND", nullptr, 0);
    return png;
}

ImageRgba8 decode_image_memory(const unsigned char* bytes, std::size_t size,
                               const std::string& what) {
    if (size == 0 || size > static_cast<std::size_t>(INT_MAX)) {
        throw std::runtime_error(what + ": image data is empty or too large");
    }
    std::uint64_t pixels = 0;
    try {
        pixels = image_pixels(bytes, size);
    } catch (const std::runtime_error& e) {
        throw std::runtime_error(what + ": " + e.what());
    }
    stereoscene::support::check_limit(what, pixels, stereoscene::support::limits().max_image_pixels,
                                      "pixels", stereoscene::support::kPixelsHint);
    int width = 0;
    int height = 0;
    int channels = 0;
    unsigned char* data =
        stbi_load_from_memory(bytes, static_cast<int>(size), &width, &height, &channels, 4);
    if (data == nullptr && pixels > 0 && stbi_failure_reason() != nullptr &&
        std::string(stbi_failure_reason()) == "outofmem") {
        throw std::runtime_error(what + ": cannot decode image: out of memory for " +
                                 std::to_string(pixels) + " pixels");
    }
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

std::uint64_t image_pixels(const unsigned char* bytes, std::size_t size) {
    // A PNG's size from its IHDR chunk (PNG spec 11.2.2): stb's header reader refuses sizes past
    // its own bound with "unknown image type", which would hide that the image is too large.
    static const unsigned char kPng[] = {0x89, 'P', 'N', 'G', '\r', '\n', 0x1a, '\n'};
    if (size >= 24 && std::memcmp(bytes, kPng, 8) == 0 && std::memcmp(bytes + 12, "IHDR", 4) == 0) {
        const auto u32 = [&](std::size_t at) {
            return (std::uint64_t{bytes[at]} << 24) | (std::uint64_t{bytes[at + 1]} << 16) |
                   (std::uint64_t{bytes[at + 2]} << 8) | std::uint64_t{bytes[at + 3]};
        };
        return u32(16) * u32(20);
    }
    int width = 0;
    int height = 0;
    int channels = 0;
    if (size == 0 || size > static_cast<std::size_t>(INT_MAX) ||
        stbi_info_from_memory(bytes, static_cast<int>(size), &width, &height, &channels) == 0) {
        const char* reason = stbi_failure_reason();
        throw std::runtime_error(std::string("cannot decode image: ") +
                                 (reason != nullptr ? reason : "unknown format"));
    }
    return static_cast<std::uint64_t>(width) * static_cast<std::uint64_t>(height);
}

ImageRgba8 decode_image(const std::filesystem::path& path) {
    const std::vector<unsigned char> bytes = stereoscene::support::read_binary_input(path);
    return decode_image_memory(bytes.data(), bytes.size(), path.string());
}

}  // namespace scene_viewer
