#pragma once

/// PNG decoding for the frames a camera writes: 8-bit grey or RGB, not interlaced. The image
/// data is inflated by libdeflate (Biggers; about twice zlib's speed) and unfiltered here (PNG
/// specification, 2nd edition, section 9); every other kind of PNG is left to OpenCV.

#include <optional>
#include <vector>

#include "cloud_analysis/io/io.hpp"

namespace cloud_analysis {

/// The channels decode_png8 returns: as stored (1 for grey, 3 for RGB), or always 3 (grey
/// repeated, as cv::IMREAD_COLOR does).
enum class PngChannels { kAsStored, kColour };

/// The image of a PNG's bytes when it is 8-bit grey or RGB without interlacing (RGB order);
/// empty for any other kind (palette, alpha, a transparent colour, 16-bit, interlaced), for a
/// file that is not a PNG, and for image data it cannot read (not inflating to exactly its rows,
/// a row naming no PNG filter): OpenCV then decodes or refuses the file as for any other. The
/// chunks' CRCs, and the image's size against the pixel limit, are the caller's to check first
/// (read_image does).
std::optional<ImageU8> decode_png8(const std::vector<unsigned char>& bytes, PngChannels channels);

}  // namespace cloud_analysis
