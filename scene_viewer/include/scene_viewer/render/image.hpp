#pragma once

/// RGBA8 image helpers for renders: atomic PNG files (encoding is assets/image_io.hpp),
/// compositing over a background and resizing.

#include <filesystem>
#include <string>

#include "scene_viewer/assets/model.hpp"
#include "scene_viewer/assets/palette.hpp"

namespace scene_viewer {

/// A width x height image filled with one colour.
ImageRgba8 make_image(int width, int height, Rgb8 colour, std::uint8_t alpha = 255);

/// Encodes (zlib level 0..9; 1 is fast) and writes atomically (temp file + rename); "-" writes
/// the PNG to stdout.
void write_png(const std::filesystem::path& path, const ImageRgba8& image, int zlib_level = 1);

/// Nearest-neighbour resize.
ImageRgba8 resize_nearest(const ImageRgba8& image, int width, int height);

/// Lays the render over a background of the same size. The render's alpha is coverage: an edge
/// pixel (MSAA or FXAA) holds alpha * model + (1 - alpha) * `clear`, so the result is
/// background + opacity * alpha * (model - background), without a halo of the clear colour;
/// where alpha is 0 it is the background. Alpha becomes 255.
void composite_over(ImageRgba8& render, const ImageRgba8& background, float opacity, Rgb8 clear);

/// The RGBA pixel at (x, y), row 0 at the top.
inline const std::uint8_t* pixel_at(const ImageRgba8& image, int x, int y) {
    return &image.pixels[(static_cast<std::size_t>(y) * image.width + x) * 4];
}

}  // namespace scene_viewer
