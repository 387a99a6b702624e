#include "cloud_analysis/io/io.hpp"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <fstream>
#include <optional>
#include <sstream>
#include <stdexcept>

#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

namespace cloud_analysis {
namespace {

cv::Mat read_raw(const std::filesystem::path& path, int flags) {
    std::error_code ec;
    if (!std::filesystem::is_regular_file(path, ec)) {
        throw std::runtime_error("cannot read image: no such file (" + path.string() + ")");
    }
    cv::Mat m;
    try {
        m = cv::imread(path.string(), flags);
    } catch (const cv::Exception& e) {
        throw std::runtime_error("cannot decode image: " + std::string(e.what()) + " (" +
                                 path.string() + ")");
    }
    if (m.empty()) {
        throw std::runtime_error("cannot decode image: unreadable or corrupt (" + path.string() +
                                 ")");
    }
    return m;
}

/// Whether a PNG file holds grey samples of at most 8 bits, from its IHDR chunk (PNG spec 11.2.2:
/// bit depth at byte 24, colour type at byte 25; type 0 is greyscale without alpha). Empty when
/// the file is not a PNG, is shorter than its header, or cannot be opened.
std::optional<bool> png_is_grey8(const std::filesystem::path& path) {
    std::ifstream in(path, std::ios::binary);
    char header[26] = {};
    if (!in.read(header, sizeof header)) return std::nullopt;
    static constexpr char kSignature[] = "\x89PNG\r\n\x1a\n";
    if (std::memcmp(header, kSignature, 8) != 0 || std::memcmp(header + 12, "IHDR", 4) != 0) {
        return std::nullopt;
    }
    const int bit_depth = static_cast<unsigned char>(header[24]);
    const int colour_type = static_cast<unsigned char>(header[25]);
    return colour_type == 0 && bit_depth <= 8;
}

std::string encode(const cv::Mat& m) {
    std::vector<std::uint8_t> bytes;
    if (!cv::imencode(".png", m, bytes)) throw std::runtime_error("PNG encoding failed");
    return std::string(bytes.begin(), bytes.end());
}

}  // namespace

std::size_t DisparityMap::valid_count() const {
    return static_cast<std::size_t>(
        std::count_if(disparity_px.begin(), disparity_px.end(), [](float d) { return d > 0.0f; }));
}

bool DisparityMap::any_valid() const {
    return std::any_of(disparity_px.begin(), disparity_px.end(), [](float d) { return d > 0.0f; });
}

ImageU8 read_image(const std::filesystem::path& path, ImageMode mode) {
    const bool as_is = mode == ImageMode::kAsIs;
    // A PNG's header says whether it is grey: one decode instead of a colour decode followed by
    // an unchanged one (a KITTI colour frame decoded in 7 ms instead of 14).
    const std::optional<bool> png_grey = as_is ? png_is_grey8(path) : std::nullopt;
    int flags = mode == ImageMode::kGrey ? cv::IMREAD_GRAYSCALE : cv::IMREAD_COLOR;
    if (png_grey && *png_grey) flags = cv::IMREAD_UNCHANGED;
    cv::Mat m = read_raw(path, flags);
    if (as_is && !png_grey && m.channels() == 3) {
        // IMREAD_COLOR turns grey files into 3 equal channels; keep them grey.
        cv::Mat grey = read_raw(path, cv::IMREAD_UNCHANGED);
        if (grey.channels() == 1 && grey.depth() == CV_8U) m = grey;
    }
    if (m.depth() != CV_8U) {
        throw std::runtime_error("cannot use image: not 8 bits per channel (" + path.string() +
                                 ")");
    }
    if (m.channels() == 3) cv::cvtColor(m, m, cv::COLOR_BGR2RGB);
    ImageU8 out;
    out.width_px = m.cols;
    out.height_px = m.rows;
    out.channels = m.channels();
    out.data.resize(static_cast<std::size_t>(m.cols) * m.rows * m.channels());
    cv::Mat wrap(m.rows, m.cols, m.type(), out.data.data());
    m.copyTo(wrap);
    return out;
}

std::string encode_png(const ImageU8& image) {
    if (image.channels != 1 && image.channels != 3) {
        throw std::invalid_argument("encode_png: image must have 1 or 3 channels");
    }
    const cv::Mat wrap(image.height_px, image.width_px, CV_8UC(image.channels),
                       const_cast<std::uint8_t*>(image.data.data()));
    if (image.channels == 1) return encode(wrap);
    cv::Mat bgr;
    cv::cvtColor(wrap, bgr, cv::COLOR_RGB2BGR);
    return encode(bgr);
}

ImageU16 read_png_u16(const std::filesystem::path& path) {
    const cv::Mat m = read_raw(path, cv::IMREAD_UNCHANGED);
    if (m.type() != CV_16UC1) {
        throw std::runtime_error("not a 16-bit single-channel PNG (" + path.string() + ")");
    }
    ImageU16 out;
    out.width_px = m.cols;
    out.height_px = m.rows;
    out.values.resize(static_cast<std::size_t>(m.cols) * m.rows);
    for (int v = 0; v < m.rows; ++v) {
        const auto* row = m.ptr<std::uint16_t>(v);
        std::copy(row, row + m.cols, out.values.data() + static_cast<std::size_t>(v) * m.cols);
    }
    return out;
}

DisparityMap read_kitti_disparity(const std::filesystem::path& path) {
    const ImageU16 raw = read_png_u16(path);
    DisparityMap out;
    out.width_px = raw.width_px;
    out.height_px = raw.height_px;
    out.disparity_px.resize(raw.values.size());
    for (std::size_t i = 0; i < raw.values.size(); ++i) {
        out.disparity_px[i] =
            raw.values[i] == 0 ? kNoDisparity : static_cast<float>(raw.values[i]) / 256.0f;
    }
    return out;
}

std::string encode_kitti_disparity_png(const DisparityMap& disparity) {
    cv::Mat m(disparity.height_px, disparity.width_px, CV_16UC1);
    for (int v = 0; v < m.rows; ++v) {
        auto* row = m.ptr<std::uint16_t>(v);
        const float* src = disparity.disparity_px.data() + static_cast<std::size_t>(v) * m.cols;
        for (int u = 0; u < m.cols; ++u) {
            const float d = src[u];
            row[u] =
                d > 0.0f
                    ? static_cast<std::uint16_t>(std::clamp(std::lround(d * 256.0f), 1L, 65535L))
                    : 0;
        }
    }
    return encode(m);
}

std::string encode_disparity_preview_png(const DisparityMap& disparity, double max_disparity_px) {
    double max_d = max_disparity_px;
    if (max_d <= 0.0) {
        for (float d : disparity.disparity_px) max_d = std::max(max_d, static_cast<double>(d));
    }
    const double scale = max_d > 0.0 ? 255.0 / max_d : 0.0;
    cv::Mat m(disparity.height_px, disparity.width_px, CV_8UC1);
    for (int v = 0; v < m.rows; ++v) {
        auto* row = m.ptr<std::uint8_t>(v);
        const float* src = disparity.disparity_px.data() + static_cast<std::size_t>(v) * m.cols;
        for (int u = 0; u < m.cols; ++u) {
            row[u] = src[u] > 0.0f
                         ? cv::saturate_cast<std::uint8_t>(static_cast<double>(src[u]) * scale)
                         : 0;
        }
    }
    return encode(m);
}

std::string read_text_file(const std::filesystem::path& path) {
    std::ifstream in(path, std::ios::binary);
    if (!in) throw std::runtime_error("cannot open file (" + path.string() + ")");
    std::ostringstream buffer;
    buffer << in.rdbuf();
    if (in.bad()) throw std::runtime_error("cannot read file (" + path.string() + ")");
    return buffer.str();
}

}  // namespace cloud_analysis
