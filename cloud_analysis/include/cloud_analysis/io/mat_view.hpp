#pragma once

/// The project's images seen as OpenCV matrices, without a copy.

#include <cstdint>

#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>

#include "cloud_analysis/io/io.hpp"

namespace cloud_analysis {

/// A cv::Mat header over `image`'s pixels (CV_8UC1 or CV_8UC3, RGB order as stored): no copy,
/// read only, valid while `image` lives and keeps its size.
inline cv::Mat mat_view(const ImageU8& image) {
    return cv::Mat(image.height_px, image.width_px, CV_8UC(image.channels),
                   const_cast<std::uint8_t*>(image.data.data()));
}

/// `image` in grey (OpenCV's RGB to grey, ITU-R 601 luma): the view itself when it is grey.
inline cv::Mat grey_of(const ImageU8& image) {
    const cv::Mat wrap = mat_view(image);
    if (image.channels == 1) return wrap;
    cv::Mat grey;
    cv::cvtColor(wrap, grey, cv::COLOR_RGB2GRAY);
    return grey;
}

}  // namespace cloud_analysis
