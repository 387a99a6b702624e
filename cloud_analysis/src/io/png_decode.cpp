#include "cloud_analysis/io/png_decode.hpp"

#include <libdeflate.h>

#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <memory>
#include <new>

namespace cloud_analysis {
namespace {

std::uint32_t be32(const unsigned char* p) {
    return (std::uint32_t{p[0]} << 24) | (std::uint32_t{p[1]} << 16) | (std::uint32_t{p[2]} << 8) |
           std::uint32_t{p[3]};
}

/// The Paeth predictor (PNG specification, section 9.4): of left a, above b and upper left c,
/// the nearest to a + b - c, ties to a then b.
int paeth(int a, int b, int c) {
    const int p = a + b - c;
    const int pa = std::abs(p - a), pb = std::abs(p - b), pc = std::abs(p - c);
    if (pa <= pb && pa <= pc) return a;
    return pb <= pc ? b : c;
}

// The filters that predict a byte from the one left of it (Sub, Average, Paeth) are reversed
// one channel at a time: each channel's running value stays in a register from pixel to pixel
// (a row of a KITTI image is 3.7 KB: its three strided passes stay in the L1 cache).

/// Sub (type 1) reversed for bpp bytes a pixel.
void unfilter_sub(const unsigned char* src, unsigned char* dst, std::size_t n, std::size_t bpp) {
    for (std::size_t c = 0; c < bpp; ++c) {
        unsigned left = 0;
        for (std::size_t i = c; i < n; i += bpp) {
            left = (left + src[i]) & 0xFFu;
            dst[i] = static_cast<unsigned char>(left);
        }
    }
}

/// Average (type 3) reversed.
void unfilter_average(const unsigned char* src, unsigned char* dst, const unsigned char* prior,
                      std::size_t n, std::size_t bpp) {
    for (std::size_t c = 0; c < bpp; ++c) {
        unsigned left = 0;
        for (std::size_t i = c; i < n; i += bpp) {
            left = (src[i] + ((left + prior[i]) >> 1)) & 0xFFu;
            dst[i] = static_cast<unsigned char>(left);
        }
    }
}

/// Paeth (type 4) reversed.
void unfilter_paeth(const unsigned char* src, unsigned char* dst, const unsigned char* prior,
                    std::size_t n, std::size_t bpp) {
    for (std::size_t c = 0; c < bpp; ++c) {
        int left = 0, upper_left = 0;
        for (std::size_t i = c; i < n; i += bpp) {
            const int above = prior[i];
            left = (src[i] + paeth(left, above, upper_left)) & 0xFF;
            upper_left = above;
            dst[i] = static_cast<unsigned char>(left);
        }
    }
}

/// Reverses the filter `type` of one row (section 9.2): `src` its filtered bytes, `dst` the
/// row out, `prior` the row above unfiltered (zeros for the first), `bpp` bytes per pixel;
/// false for a type PNG does not have.
bool unfilter(unsigned char type, const unsigned char* src, unsigned char* dst,
              const unsigned char* prior, std::size_t n, std::size_t bpp) {
    switch (type) {
        case 0:
            std::memcpy(dst, src, n);
            return true;
        case 1:
            unfilter_sub(src, dst, n, bpp);
            return true;
        case 2:
            for (std::size_t i = 0; i < n; ++i)
                dst[i] = static_cast<unsigned char>(src[i] + prior[i]);
            return true;
        case 3:
            unfilter_average(src, dst, prior, n, bpp);
            return true;
        case 4:
            unfilter_paeth(src, dst, prior, n, bpp);
            return true;
        default:
            return false;
    }
}

struct DecompressorFree {
    void operator()(libdeflate_decompressor* d) const { libdeflate_free_decompressor(d); }
};

}  // namespace

std::optional<ImageU8> decode_png8(const std::vector<unsigned char>& bytes, PngChannels channels) {
    static constexpr char kSignature[] = "\x89PNG\r\n\x1a\n";
    // Signature, then IHDR (section 11.2.2): width, height, bit depth, colour type,
    // compression, filter method, interlace method.
    if (bytes.size() < 33 || std::memcmp(bytes.data(), kSignature, 8) != 0 ||
        std::memcmp(bytes.data() + 12, "IHDR", 4) != 0) {
        return std::nullopt;
    }
    const std::uint32_t width = be32(bytes.data() + 16), height = be32(bytes.data() + 20);
    const unsigned char depth = bytes[24], colour_type = bytes[25];
    if (depth != 8 || (colour_type != 0 && colour_type != 2) || bytes[26] != 0 || bytes[27] != 0 ||
        bytes[28] != 0 || width == 0 || height == 0 || width > (1u << 24) || height > (1u << 24)) {
        return std::nullopt;
    }
    const std::size_t bpp = colour_type == 2 ? 3 : 1;
    // The image data: the IDAT chunks' contents in order, one zlib stream (section 10).
    std::vector<unsigned char> stream;
    for (std::size_t at = 8; at + 12 <= bytes.size();) {
        const std::uint32_t length = be32(bytes.data() + at);
        if (length > bytes.size() - at - 12) return std::nullopt;
        const unsigned char* type = bytes.data() + at + 4;
        if (std::memcmp(type, "IDAT", 4) == 0)
            stream.insert(stream.end(), type + 4, type + 4 + length);
        // A transparent colour makes OpenCV add an alpha channel when the file is read as is.
        if (std::memcmp(type, "tRNS", 4) == 0) return std::nullopt;
        if (std::memcmp(type, "IEND", 4) == 0) break;
        at += 12 + std::size_t{length};
    }
    const std::size_t stride = 1 + std::size_t{width} * bpp;
    std::vector<unsigned char> raw(stride * height);
    const std::unique_ptr<libdeflate_decompressor, DecompressorFree> inflater(
        libdeflate_alloc_decompressor());
    if (!inflater) throw std::bad_alloc();
    std::size_t inflated = 0;
    if (libdeflate_zlib_decompress(inflater.get(), stream.data(), stream.size(), raw.data(),
                                   raw.size(), &inflated) != LIBDEFLATE_SUCCESS ||
        inflated != raw.size()) {
        return std::nullopt;
    }
    ImageU8 out;
    out.width_px = static_cast<int>(width);
    out.height_px = static_cast<int>(height);
    out.channels = channels == PngChannels::kColour ? 3 : static_cast<int>(bpp);
    out.data.resize(std::size_t{width} * height * static_cast<std::size_t>(out.channels));
    // Rows are unfiltered straight into the image, or, when grey becomes colour, into two
    // alternating rows that are then repeated into three channels.
    const std::size_t n = stride - 1;
    const bool expand = static_cast<std::size_t>(out.channels) != bpp;
    std::vector<unsigned char> rows(expand ? 2 * n : 0), zeros(n, 0);
    const unsigned char* prior = zeros.data();
    for (std::size_t v = 0; v < height; ++v) {
        const unsigned char* src = raw.data() + v * stride;
        unsigned char* dst = expand ? rows.data() + (v % 2) * n : out.data.data() + v * n;
        if (!unfilter(src[0], src + 1, dst, prior, n, bpp)) return std::nullopt;
        prior = dst;
        if (expand) {
            unsigned char* rgb = out.data.data() + v * 3 * n;
            for (std::size_t u = 0; u < n; ++u)
                rgb[3 * u] = rgb[3 * u + 1] = rgb[3 * u + 2] = dst[u];
        }
    }
    return out;
}

}  // namespace cloud_analysis
