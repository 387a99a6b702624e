#pragma once

/// PNG encoding and image decoding for the whole scene_viewer library, through Debian's
/// compiled stb (libstb.so). Nobody defines STB_IMAGE_IMPLEMENTATION or
/// STB_IMAGE_WRITE_IMPLEMENTATION: the implementation is linked, not compiled in.

#include <cstddef>
#include <filesystem>
#include <string>
#include <vector>

#include "scene_viewer/assets/model.hpp"

namespace scene_viewer {

/// Encodes an RGBA8 image (rows top to bottom) as PNG bytes; zlib_level 0..9 (stb's default
/// is 8). Throws std::invalid_argument for an empty or inconsistent image or a bad level.
std::vector<unsigned char> encode_png(const ImageRgba8& image, int zlib_level = 6);

/// Decodes a PNG/JPEG/BMP/TGA file into RGBA8 (rows top to bottom); throws std::runtime_error
/// "<file>: <reason>".
ImageRgba8 decode_image(const std::filesystem::path& path);

/// Decodes image bytes held in memory into RGBA8; `what` names the source in errors.
ImageRgba8 decode_image_memory(const unsigned char* bytes, std::size_t size,
                               const std::string& what);

}  // namespace scene_viewer
