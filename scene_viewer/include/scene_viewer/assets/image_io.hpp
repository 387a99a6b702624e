#pragma once

/// PNG encoding (zlib, one encoder for 8- and 16-bit images) and image decoding through
/// Debian's compiled stb (libstb.so). Nobody defines STB_IMAGE_IMPLEMENTATION: the
/// implementation is linked, not compiled in.

#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>

#include "scene_viewer/assets/model.hpp"

namespace scene_viewer {

/// Encodes an RGBA8 image (rows top to bottom) as PNG bytes; zlib_level 0..9 (1 is fast).
/// Throws std::invalid_argument for an empty or inconsistent image or a bad level.
std::vector<unsigned char> encode_png(const ImageRgba8& image, int zlib_level = 6);

/// Encodes PNG (ISO/IEC 15948) from raw sample bytes: `height` rows of width * bytes_per_pixel
/// bytes, 16-bit samples big-endian; `colour_type` as in IHDR (0 grey, 2 RGB, 6 RGBA). Every
/// row uses the Sub filter (fast, and nearly as small as adaptive filtering on renders).
std::vector<unsigned char> encode_png_samples(const unsigned char* rows, int width, int height,
                                              int bit_depth, int colour_type, int bytes_per_pixel,
                                              int zlib_level);

/// Decodes a PNG/JPEG/BMP/TGA file into RGBA8 (rows top to bottom), read through the bounded
/// reader and refused before decoding when its header promises more than
/// support::limits().max_image_pixels; throws std::runtime_error "<file>: <reason>".
ImageRgba8 decode_image(const std::filesystem::path& path);

/// Width x height promised by an image's header, read without decoding; throws
/// std::runtime_error when the header cannot be read.
std::uint64_t image_pixels(const unsigned char* bytes, std::size_t size);

/// Decodes image bytes held in memory into RGBA8 (refused beyond the pixel limit before
/// decoding); `what` names the source in errors.
ImageRgba8 decode_image_memory(const unsigned char* bytes, std::size_t size,
                               const std::string& what);

}  // namespace scene_viewer
