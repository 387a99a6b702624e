#include <cstdint>
#include <random>
#include <string>
#include <vector>

#include <zlib.h>
#include <catch2/catch.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "cloud_analysis/io/png_decode.hpp"

using namespace cloud_analysis;

namespace {

void put32(std::vector<unsigned char>& out, std::uint32_t v) {
    for (int s = 24; s >= 0; s -= 8) out.push_back(static_cast<unsigned char>(v >> s));
}

void chunk(std::vector<unsigned char>& out, const char* type,
           const std::vector<unsigned char>& data) {
    put32(out, static_cast<std::uint32_t>(data.size()));
    std::vector<unsigned char> body(type, type + 4);
    body.insert(body.end(), data.begin(), data.end());
    out.insert(out.end(), body.begin(), body.end());
    put32(out, static_cast<std::uint32_t>(crc32(0L, body.data(), static_cast<uInt>(body.size()))));
}

int paeth(int a, int b, int c) {
    const int p = a + b - c, pa = std::abs(p - a), pb = std::abs(p - b), pc = std::abs(p - c);
    return pa <= pb && pa <= pc ? a : (pb <= pc ? b : c);
}

/// A PNG of `pixels` (w x h, `channels` 1 or 3 interleaved), row v filtered with filter
/// `filters[v % filters.size()]` (PNG specification section 9), its data in IDAT chunks of at
/// most `idat_bytes`; `depth`, `colour_type` and `interlace` as written in IHDR.
std::vector<unsigned char> make_png(const std::vector<unsigned char>& pixels, int w, int h,
                                    int channels, const std::vector<int>& filters,
                                    std::size_t idat_bytes = 1 << 20, int depth = 8,
                                    int colour_type = -1, int interlace = 0) {
    const auto bpp = static_cast<std::size_t>(channels);
    const std::size_t n = static_cast<std::size_t>(w) * bpp;
    std::vector<unsigned char> raw;
    for (int v = 0; v < h; ++v) {
        const int f = filters[static_cast<std::size_t>(v) % filters.size()];
        raw.push_back(static_cast<unsigned char>(f));
        const unsigned char* row = pixels.data() + static_cast<std::size_t>(v) * n;
        for (std::size_t i = 0; i < n; ++i) {
            const int a = i >= bpp ? row[i - bpp] : 0;
            const int b = v > 0 ? row[i - n] : 0;
            const int c = i >= bpp && v > 0 ? row[i - n - bpp] : 0;
            const int predictor = f == 1   ? a
                                  : f == 2 ? b
                                  : f == 3 ? (a + b) / 2
                                  : f == 4 ? paeth(a, b, c)
                                           : 0;
            raw.push_back(static_cast<unsigned char>(row[i] - predictor));
        }
    }
    uLongf size = compressBound(static_cast<uLong>(raw.size()));
    std::vector<unsigned char> z(size);
    REQUIRE(compress2(z.data(), &size, raw.data(), static_cast<uLong>(raw.size()), 6) == Z_OK);
    z.resize(size);
    std::vector<unsigned char> png = {0x89, 'P', 'N', 'G', '\r', '\n', 0x1a, '\n'};
    std::vector<unsigned char> ihdr;
    put32(ihdr, static_cast<std::uint32_t>(w));
    put32(ihdr, static_cast<std::uint32_t>(h));
    ihdr.push_back(static_cast<unsigned char>(depth));
    ihdr.push_back(
        static_cast<unsigned char>(colour_type >= 0 ? colour_type : (channels == 3 ? 2 : 0)));
    ihdr.insert(ihdr.end(), {0, 0, static_cast<unsigned char>(interlace)});
    chunk(png, "IHDR", ihdr);
    for (std::size_t at = 0; at < z.size(); at += idat_bytes) {
        const std::size_t end = std::min(z.size(), at + idat_bytes);
        chunk(png, "IDAT",
              std::vector<unsigned char>(z.begin() + static_cast<long>(at),
                                         z.begin() + static_cast<long>(end)));
    }
    chunk(png, "IEND", {});
    return png;
}

std::vector<unsigned char> random_pixels(int w, int h, int channels, unsigned seed) {
    std::mt19937 rng(seed);
    std::uniform_int_distribution<int> byte(0, 255);
    std::vector<unsigned char> p(static_cast<std::size_t>(w * h * channels));
    for (auto& v : p) v = static_cast<unsigned char>(byte(rng));
    return p;
}

/// What OpenCV's decoder (libpng) makes of the bytes, in RGB order.
std::vector<unsigned char> opencv_decode(const std::vector<unsigned char>& png, int flags) {
    cv::Mat m = cv::imdecode(png, flags);
    REQUIRE(!m.empty());
    if (m.channels() == 3) cv::cvtColor(m, m, cv::COLOR_BGR2RGB);
    return std::vector<unsigned char>(m.data, m.data + m.total() * m.elemSize());
}

}  // namespace

TEST_CASE("camera PNGs decode as libpng decodes them, every row filter and split image data",
          "[io][png]") {
    for (const int channels : {1, 3}) {
        const int w = 37, h = 23;
        const auto pixels = random_pixels(w, h, channels, 5u + static_cast<unsigned>(channels));
        const auto png = make_png(pixels, w, h, channels, {0, 1, 2, 3, 4, 4, 3, 1}, 100);
        const std::optional<ImageU8> image = decode_png8(png, PngChannels::kAsStored);
        REQUIRE(image);
        CHECK(image->width_px == w);
        CHECK(image->height_px == h);
        CHECK(image->channels == channels);
        CHECK(image->data == pixels);
        CHECK(image->data == opencv_decode(png, cv::IMREAD_UNCHANGED));
        // As colour, grey is repeated in the three channels, as cv::IMREAD_COLOR does.
        const std::optional<ImageU8> colour = decode_png8(png, PngChannels::kColour);
        REQUIRE(colour);
        CHECK(colour->channels == 3);
        CHECK(colour->data == opencv_decode(png, cv::IMREAD_COLOR));
    }
}

TEST_CASE("PNGs other than 8-bit grey or RGB without interlacing are left to OpenCV", "[io][png]") {
    const auto pixels = random_pixels(8, 4, 3, 1);
    CHECK_FALSE(decode_png8(make_png(pixels, 8, 4, 3, {0}, 1 << 20, 8, 2, 1),
                            PngChannels::kAsStored));  // Adam7
    CHECK_FALSE(decode_png8(make_png(pixels, 4, 4, 3, {0}, 1 << 20, 16, 2),
                            PngChannels::kAsStored));  // 16-bit
    CHECK_FALSE(decode_png8(make_png(pixels, 6, 4, 4, {0}, 1 << 20, 8, 6),
                            PngChannels::kAsStored));  // RGBA
    CHECK_FALSE(decode_png8(make_png(pixels, 24, 4, 1, {0}, 1 << 20, 8, 3),
                            PngChannels::kAsStored));  // palette
    CHECK_FALSE(decode_png8({'J', 'P', 'E', 'G'}, PngChannels::kAsStored));
    // A transparent colour (tRNS): read as is, OpenCV adds an alpha channel.
    std::vector<unsigned char> keyed = make_png(pixels, 8, 4, 3, {0});
    std::vector<unsigned char> trns;
    chunk(trns, "tRNS", {0, 1, 0, 2, 0, 3});
    keyed.insert(keyed.begin() + 33, trns.begin(), trns.end());
    CHECK(cv::imdecode(keyed, cv::IMREAD_UNCHANGED).channels() == 4);
    CHECK_FALSE(decode_png8(keyed, PngChannels::kAsStored));
}

TEST_CASE("a PNG whose image data the decoder cannot read is left to OpenCV", "[io][png]") {
    const auto pixels = random_pixels(16, 8, 3, 2);
    // A row naming filter 5, which PNG does not have: libpng refuses it too.
    std::vector<unsigned char> png = make_png(pixels, 16, 8, 3, {5});
    CHECK_FALSE(decode_png8(png, PngChannels::kAsStored));
    CHECK(cv::imdecode(png, cv::IMREAD_UNCHANGED).empty());
    // Image data one row short of the header's height (IHDR says 9 rows, its CRC redone).
    png = make_png(pixels, 16, 8, 3, {1});
    png[23] = 9;
    const auto crc = static_cast<std::uint32_t>(crc32(0L, png.data() + 12, 17));
    for (int k = 0; k < 4; ++k) {
        png[29 + static_cast<std::size_t>(k)] = static_cast<unsigned char>(crc >> (24 - 8 * k));
    }
    CHECK_FALSE(decode_png8(png, PngChannels::kAsStored));
    // A chunk running past the end of the file.
    png = make_png(pixels, 16, 8, 3, {1});
    png.resize(png.size() - 20);
    CHECK_FALSE(decode_png8(png, PngChannels::kAsStored));
}
