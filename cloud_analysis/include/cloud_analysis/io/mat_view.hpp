#pragma once

/// The project's images seen as OpenCV matrices, without a copy.

#include <cstdint>

#include <opencv2/core.hpp>

#include "cloud_analysis/io/io.hpp"

namespace cloud_analysis {

/// A cv::Mat header over `image`'s pixels (CV_8UC1 or CV_8UC3, RGB order as stored): no copy,
/// read only, valid while `image` lives and keeps its size.
inline cv::Mat mat_view(const ImageU8& image) {
    return cv::Mat(image.height_px, image.width_px, CV_8UC(image.channels),
                   const_cast<std::uint8_t*>(image.data.data()));
}

}  // namespace cloud_analysis
