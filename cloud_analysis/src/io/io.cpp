#include "cloud_analysis/io/io.hpp"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <fstream>
#include <new>
#include <optional>
#include <sstream>
#include <stdexcept>

#include <zlib.h>
#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "cloud_analysis/io/mat_view.hpp"
#include "cloud_analysis/io/png_decode.hpp"
#include "stereoscene/support/file_read.hpp"
#include "stereoscene/support/limits.hpp"

namespace cloud_analysis {
namespace {

/// Width x height from a PNG's IHDR or a JPEG's first start-of-frame marker, read without
/// decoding; empty for other formats or a header cut short.
std::optional<std::uint64_t> header_pixels(const std::vector<unsigned char>& b) {
    auto u16 = [&](std::size_t at) { return (std::uint64_t{b[at]} << 8) | b[at + 1]; };
    auto u32 = [&](std::size_t at) { return (u16(at) << 16) | u16(at + 2); };
    if (b.size() >= 24 && std::memcmp(b.data(), "\x89PNG\r\n\x1a\n", 8) == 0) {
        return u32(16) * u32(20);
    }
    if (b.size() < 4 || b[0] != 0xFF || b[1] != 0xD8) return std::nullopt;
    std::size_t at = 2;
    while (at + 9 < b.size() && b[at] == 0xFF) {
        const unsigned marker = b[at + 1];
        const bool sof =
            marker >= 0xC0 && marker <= 0xCF && marker != 0xC4 && marker != 0xC8 && marker != 0xCC;
        if (sof) return u16(at + 5) * u16(at + 7);
        at += 2 + u16(at + 2);
    }
    return std::nullopt;
}

/// CRC-32 of PNG chunks (ISO 3309, the polynomial of PNG spec section 5.5), by zlib's table-
/// driven crc32 (a byte-at-a-time loop cost ~4 % of a KITTI batch frame's CPU).
std::uint32_t png_crc(const unsigned char* p, std::size_t n) {
    return static_cast<std::uint32_t>(crc32_z(crc32_z(0L, Z_NULL, 0), p, n));
}

/// Walks a PNG's chunks (PNG spec section 5.3): each inside the file with its CRC right, IHDR
/// first, IEND last. A truncated or corrupted file is named here in one line instead of by
/// libpng's own "libpng error" line on stderr before the decoder gives up.
void check_png_chunks(const std::vector<unsigned char>& b, const std::filesystem::path& path) {
    auto fail = [&](const std::string& why) {
        throw std::runtime_error("cannot decode image: " + why + " (" + path.string() + ")");
    };
    auto u32 = [&](std::size_t at) {
        return (std::uint32_t{b[at]} << 24) | (std::uint32_t{b[at + 1]} << 16) |
               (std::uint32_t{b[at + 2]} << 8) | std::uint32_t{b[at + 3]};
    };
    std::size_t at = 8;
    bool first = true;
    for (;;) {
        if (b.size() - at < 12) fail("truncated PNG (no IEND chunk)");
        const std::uint32_t length = u32(at);
        if (length > b.size() - at - 12) fail("truncated PNG (a chunk runs past the end)");
        const unsigned char* type = b.data() + at + 4;
        if (png_crc(type, 4 + std::size_t{length}) != u32(at + 8 + length)) {
            fail("corrupt PNG (chunk " + std::string(reinterpret_cast<const char*>(type), 4) +
                 " fails its CRC)");
        }
        if (first && std::memcmp(type, "IHDR", 4) != 0) fail("corrupt PNG (IHDR is not first)");
        first = false;
        at += 12 + std::size_t{length};
        if (std::memcmp(type, "IEND", 4) == 0) return;
    }
}

/// The bytes of an image file, through the bounded reader, refused when the header promises
/// more pixels than the limit allows.
std::vector<unsigned char> read_image_bytes(const std::filesystem::path& path) {
    std::vector<unsigned char> bytes = stereoscene::support::read_binary_input(path);
    if (bytes.size() >= 8 && std::memcmp(bytes.data(), "\x89PNG\r\n\x1a\n", 8) == 0) {
        check_png_chunks(bytes, path);
    }
    if (const auto pixels = header_pixels(bytes)) {
        stereoscene::support::check_limit(path.string(), *pixels,
                                          stereoscene::support::limits().max_image_pixels, "pixels",
                                          stereoscene::support::kPixelsHint);
    }
    return bytes;
}

cv::Mat decode_raw(const std::vector<unsigned char>& bytes, const std::filesystem::path& path,
                   int flags) {
    cv::Mat m;
    try {
        m = cv::imdecode(bytes, flags);
    } catch (const cv::Exception& e) {
        throw std::runtime_error("cannot decode image: " + e.msg + " (" + path.string() + ")");
    } catch (const std::bad_alloc&) {
        throw std::runtime_error("cannot decode image: out of memory (" + path.string() + ")");
    }
    if (m.empty()) {
        throw std::runtime_error("cannot decode image: unreadable or corrupt (" + path.string() +
                                 ")");
    }
    stereoscene::support::check_limit(
        path.string(), static_cast<std::uint64_t>(m.rows) * static_cast<std::uint64_t>(m.cols),
        stereoscene::support::limits().max_image_pixels, "pixels",
        stereoscene::support::kPixelsHint);
    return m;
}

cv::Mat read_raw(const std::filesystem::path& path, int flags) {
    return decode_raw(read_image_bytes(path), path, flags);
}

/// Whether PNG bytes hold grey samples of at most 8 bits, from the IHDR chunk (PNG spec 11.2.2:
/// bit depth at byte 24, colour type at byte 25; type 0 is greyscale without alpha). Empty when
/// the bytes are not a PNG or are shorter than its header.
std::optional<bool> png_is_grey8(const std::vector<unsigned char>& bytes) {
    static constexpr char kSignature[] = "\x89PNG\r\n\x1a\n";
    if (bytes.size() < 26 || std::memcmp(bytes.data(), kSignature, 8) != 0 ||
        std::memcmp(bytes.data() + 12, "IHDR", 4) != 0) {
        return std::nullopt;
    }
    return bytes[25] == 0 && bytes[24] <= 8;
}

/// A camera frame's PNG decoded by decode_png8 (8-bit grey or RGB, not interlaced) in `mode`;
/// empty for other files, and for colour files read as grey (OpenCV's conversion decides those
/// values).
std::optional<ImageU8> fast_png(const std::vector<unsigned char>& bytes,
                                const std::filesystem::path& path, ImageMode mode) {
    try {
        if (mode != ImageMode::kGrey) {
            return decode_png8(
                bytes, mode == ImageMode::kColour ? PngChannels::kColour : PngChannels::kAsStored);
        }
        const std::optional<bool> grey = png_is_grey8(bytes);
        if (grey && *grey) return decode_png8(bytes, PngChannels::kAsStored);
    } catch (const std::bad_alloc&) {
        throw std::runtime_error("cannot decode image: out of memory (" + path.string() + ")");
    }
    return std::nullopt;
}

/// The samples of a 16-bit single-channel image.
ImageU16 u16_of(const cv::Mat& m) {
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
    const std::vector<unsigned char> bytes = read_image_bytes(path);
    if (const std::optional<ImageU8> fast = fast_png(bytes, path, mode)) return *fast;
    const std::optional<bool> png_grey = as_is ? png_is_grey8(bytes) : std::nullopt;
    // IMREAD_ANYDEPTH: a 16-bit file keeps its depth and is refused below, instead of OpenCV's
    // silent shift to the top 8 bits (a 12-bit camera's frames would come out nearly black).
    int flags =
        (mode == ImageMode::kGrey ? cv::IMREAD_GRAYSCALE : cv::IMREAD_COLOR) | cv::IMREAD_ANYDEPTH;
    if (png_grey && *png_grey) flags = cv::IMREAD_UNCHANGED;
    cv::Mat m = decode_raw(bytes, path, flags);
    if (as_is && !png_grey && m.channels() == 3) {
        // IMREAD_COLOR turns grey files into 3 equal channels; keep them grey.
        cv::Mat grey = decode_raw(bytes, path, cv::IMREAD_UNCHANGED);
        if (grey.channels() == 1 && grey.depth() == CV_8U) m = grey;
    }
    if (m.depth() != CV_8U) {
        const int bits = m.depth() == CV_16U || m.depth() == CV_16S ? 16 : 32;
        throw std::runtime_error("cannot use image: " + std::to_string(bits) +
                                 "-bit samples refused, the stages work on 8-bit values; "
                                 "convert it to 8 bits per channel first (" +
                                 path.string() + ")");
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
    const cv::Mat wrap = mat_view(image);
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
    return u16_of(m);
}

ImageU16 read_instance_png(const std::filesystem::path& path) {
    try {
        return read_png_u16(path);
    } catch (const std::exception& e) {
        throw std::runtime_error(std::string("cannot read instance image: ") + e.what());
    }
}

IdImage read_id_image(const std::filesystem::path& path) {
    cv::Mat m = read_raw(path, cv::IMREAD_UNCHANGED);
    IdImage out;
    if (m.type() == CV_16UC1) {
        out.ids = u16_of(m);
        return out;
    }
    if (m.type() != CV_8UC1 && m.type() != CV_8UC3) {
        throw std::runtime_error(
            "cannot use instance image: neither 16-bit single-channel ids nor 8-bit RGB colours "
            "(" +
            path.string() + ")");
    }
    if (m.channels() == 3) cv::cvtColor(m, m, cv::COLOR_BGR2RGB);
    out.colour.width_px = m.cols;
    out.colour.height_px = m.rows;
    out.colour.channels = m.channels();
    out.colour.data.resize(static_cast<std::size_t>(m.cols) * m.rows * m.channels());
    cv::Mat wrap(m.rows, m.cols, m.type(), out.colour.data.data());
    m.copyTo(wrap);
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

std::string encode_png_u16(const ImageU16& image) {
    if (image.values.size() != static_cast<std::size_t>(image.width_px) * image.height_px ||
        image.width_px <= 0 || image.height_px <= 0) {
        throw std::invalid_argument("encode_png_u16: image size does not match its samples");
    }
    // imencode reads the samples; the Mat only wraps them.
    const cv::Mat m(image.height_px, image.width_px, CV_16UC1,
                    const_cast<std::uint16_t*>(image.values.data()));
    return encode(m);
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
    return stereoscene::support::read_text_input(path);
}

}  // namespace cloud_analysis
