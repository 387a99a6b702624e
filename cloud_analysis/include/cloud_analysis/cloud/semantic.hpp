#pragma once

/// Semantic association: palette files (colour -> class) and the per-pixel class of a semantic
/// image. Palettes live in assets/palettes/*.json; the format is documented in docs/clouds.md.

#include <cstddef>
#include <filesystem>
#include <string>
#include <string_view>
#include <vector>

#include "cloud_analysis/cloud/types.hpp"
#include "cloud_analysis/io/io.hpp"

namespace cloud_analysis {

/// Parses palette JSON: {"name": "...", "classes": [{"name", "id", "colour": [r,g,b],
/// "thing"}...]}. Throws std::runtime_error "<origin>: <json pointer>: <rule>" when malformed
/// or when two classes share a colour.
Palette parse_palette(std::string_view json_text, const std::string& origin);

/// Loads a palette file. A bare name without extension or slash ("cityscapes", "carla",
/// "thesis") is looked up in the bundled palette folder.
Palette load_palette(const std::string& name_or_path);

/// Folder of the bundled palettes: palettes/ in stereoscene::support::asset_dir().
std::filesystem::path bundled_palette_dir();

/// Index of the class with this colour, or kVoidClass.
std::uint16_t find_colour(const Palette& palette, const Rgb& colour);

/// Index of the class with this name, or kVoidClass.
std::uint16_t find_class(const Palette& palette, std::string_view name);

/// Per-pixel class index of a semantic image.
struct ClassImage {
    int width_px = 0;   ///< columns
    int height_px = 0;  ///< rows
    std::vector<std::uint16_t>
        class_index;              ///< row-major index into Palette::classes or kVoidClass
    std::size_t void_pixels = 0;  ///< pixels whose colour is not in the palette
};

/// Maps each pixel's colour through the palette (the semantic image must be 3-channel RGB).
ClassImage classify_pixels(const ImageU8& semantic_rgb, const Palette& palette);

}  // namespace cloud_analysis
