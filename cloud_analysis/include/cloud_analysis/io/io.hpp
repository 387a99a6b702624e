#pragma once

/// Images and disparity maps in memory (plain structs, no OpenCV in the interface) and their
/// file formats: PNG/JPG images, KITTI 16-bit disparity PNG, 8-bit preview PNG.

#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>

namespace cloud_analysis {

/// An 8-bit image, rows top to bottom, channels interleaved in RGB order (or 1 grey channel).
struct ImageU8 {
    int width_px = 0;                ///< columns
    int height_px = 0;               ///< rows
    int channels = 0;                ///< 1 (grey) or 3 (RGB)
    std::vector<std::uint8_t> data;  ///< width_px * height_px * channels bytes
    bool empty() const { return data.empty(); }
    const std::uint8_t* at(int u, int v) const {
        return data.data() + (static_cast<std::size_t>(v) * width_px + u) * channels;
    }
};

/// Dense disparity of the left image in pixels; kNoDisparity where there is no value.
struct DisparityMap {
    int width_px = 0;                 ///< columns
    int height_px = 0;                ///< rows
    std::vector<float> disparity_px;  ///< row-major, left image pixel grid
    std::size_t valid_count() const;  ///< pixels holding a value
    bool any_valid() const;           ///< whether any pixel holds a value (stops at the first)
};

/// Single-channel 16-bit image, row-major (KITTI disparity and instance PNGs).
struct ImageU16 {
    int width_px = 0;                   ///< columns
    int height_px = 0;                  ///< rows
    std::vector<std::uint16_t> values;  ///< width_px * height_px samples
};

/// Marker of a pixel without disparity (any value <= 0 is treated as missing).
inline constexpr float kNoDisparity = -1.0f;

/// How read_image converts the file's channels.
enum class ImageMode { kColour, kGrey, kAsIs };

/// Reads a PNG/JPG (any format OpenCV decodes); throws std::runtime_error naming the file when it
/// is missing, unreadable or corrupt. kAsIs keeps grey as 1 channel and colour as RGB.
ImageU8 read_image(const std::filesystem::path& path, ImageMode mode = ImageMode::kAsIs);

/// PNG bytes of an 8-bit image (1 or 3 channels, RGB order).
std::string encode_png(const ImageU8& image);

/// Reads a KITTI disparity PNG (uint16, d = v / 256, 0 = no value).
DisparityMap read_kitti_disparity(const std::filesystem::path& path);

/// Reads a 16-bit single-channel PNG; throws std::runtime_error naming the file when it is
/// missing, corrupt or of another type.
ImageU16 read_png_u16(const std::filesystem::path& path);

/// An image whose samples are ids rather than light: 16-bit single-channel (ids) or 8-bit
/// with 1 or 3 channels (RGB order), exactly one of the two filled.
struct IdImage {
    ImageU16 ids;    ///< 16-bit samples; empty values when the file has 8-bit samples
    ImageU8 colour;  ///< 8-bit samples; empty when the file has 16-bit samples
    bool has_ids() const { return !ids.values.empty(); }
    int width_px() const { return has_ids() ? ids.width_px : colour.width_px; }
    int height_px() const { return has_ids() ? ids.height_px : colour.height_px; }
};

/// Reads an instance image as stored (no conversion of depth or channels); throws
/// std::runtime_error naming the file when it is missing, corrupt, or neither 16-bit
/// single-channel nor 8-bit grey or RGB.
IdImage read_id_image(const std::filesystem::path& path);

/// Reads a 16-bit single-channel instance PNG (KITTI's, scene-render sensors' ground truth);
/// throws std::runtime_error "cannot read instance image: <reason>" naming the file.
ImageU16 read_instance_png(const std::filesystem::path& path);

/// PNG bytes of a 16-bit single-channel image.
std::string encode_png_u16(const ImageU16& image);

/// KITTI 16-bit disparity PNG bytes: v = round(d * 256) clamped to 65535, 0 where missing.
std::string encode_kitti_disparity_png(const DisparityMap& disparity);

/// Viewable 8-bit PNG as the thesis saved it: d scaled by 255 / max_disparity_px, 0 where
/// missing. max_disparity_px <= 0 uses the map's own maximum.
std::string encode_disparity_preview_png(const DisparityMap& disparity,
                                         double max_disparity_px = 0.0);

/// Reads a whole text file into memory through the bounded reader (regular files only, at most
/// support::limits().max_text_bytes); throws support::FileError "<file>: <reason>".
std::string read_text_file(const std::filesystem::path& path);

}  // namespace cloud_analysis
