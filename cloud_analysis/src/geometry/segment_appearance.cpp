// What the segment classifier reads beside the rules' measurements: each segment's colour,
// texture and surface roughness, gathered in one pass over its pixels.
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <vector>

#include "derive_semantics_internal.hpp"

namespace cloud_analysis::geometry {
namespace {

/// Disparity steps between neighbours larger than this make a surface rough, px: a car's panel
/// changes by less between neighbouring pixels at any range the path sees.
constexpr float kRoughStepPx = 0.3f;
/// Added to the mean grey level before dividing by it: keeps dark segments' ratios finite.
constexpr double kLumaFloor = 5.0;

/// Per segment, in integers where they can be: colour sums are of 8-bit channels, and a
/// pixel's "level" is the sum of its three channels (three times its grey level).
struct Sums {
    std::size_t n = 0, coloured = 0;
    int u0 = 1 << 30, v0 = 1 << 30, u1 = -1, v1 = -1;
    std::int64_t channel[3] = {0, 0, 0};
    std::int64_t level = 0, level2 = 0, grad = 0;
    std::size_t grad_pairs = 0, pairs_h = 0, rough_h = 0, pairs_v = 0, rough_v = 0;
    std::vector<float> disparities;
};

/// The left image's pixels as three channels each: its own bytes when it is RGB, else a grey
/// image repeated into `grey3`; null without an image of the disparity's size.
const std::uint8_t* rgb_of(const ImageU8& left, int w, int h, std::vector<std::uint8_t>& grey3) {
    if (left.empty() || left.width_px != w || left.height_px != h) return nullptr;
    if (left.channels == 3) return left.data.data();
    grey3.resize(left.data.size() * 3);
    for (std::size_t p = 0; p < left.data.size(); ++p) {
        grey3[3 * p] = grey3[3 * p + 1] = grey3[3 * p + 2] = left.data[p];
    }
    return grey3.data();
}

double quantile_of(std::vector<float>& v, double q) {
    const auto k = static_cast<std::ptrdiff_t>(q * static_cast<double>(v.size() - 1));
    std::nth_element(v.begin(), v.begin() + k, v.end());
    return v[static_cast<std::size_t>(k)];
}

void finish(Sums& s, Segment& seg) {
    if (s.n == 0) return;
    const double n = static_cast<double>(s.n);
    const double area = static_cast<double>(s.u1 - s.u0 + 1) * (s.v1 - s.v0 + 1);
    seg.fill = n / area;
    if (s.coloured > 0) {
        // Chromaticity of the summed colour, each channel lifted by one level (black is grey).
        const double c = static_cast<double>(s.coloured);
        const double all = static_cast<double>(s.level) + 3.0 * c;
        seg.chroma_r = (static_cast<double>(s.channel[0]) + c) / all;
        seg.chroma_g = (static_cast<double>(s.channel[1]) + c) / all;
        seg.chroma_b = (static_cast<double>(s.channel[2]) + c) / all;
        seg.luma = static_cast<double>(s.level) / (3.0 * c);
        const double mean2 = static_cast<double>(s.level2) / (9.0 * c);
        seg.luma_cv =
            std::sqrt(std::max(0.0, mean2 - seg.luma * seg.luma)) / (seg.luma + kLumaFloor);
        seg.grad = s.grad_pairs
                       ? static_cast<double>(s.grad) / (3.0 * static_cast<double>(s.grad_pairs)) /
                             (seg.luma + kLumaFloor)
                       : 0.0;
    }
    seg.rough_h = s.pairs_h ? static_cast<double>(s.rough_h) / static_cast<double>(s.pairs_h) : 0.0;
    seg.rough_v = s.pairs_v ? static_cast<double>(s.rough_v) / static_cast<double>(s.pairs_v) : 0.0;
    const double median = quantile_of(s.disparities, 0.5);
    if (median > 0.0) {
        const double hi = quantile_of(s.disparities, 0.9), lo = quantile_of(s.disparities, 0.1);
        seg.disparity_spread = (hi - lo) / median;
    }
}

}  // namespace

void measure_appearance(const Grid& grid, const DisparityMap& disparity, const ImageU8& left,
                        const std::vector<char>& fresh, std::vector<Segment>& segments) {
    const int w = disparity.width_px, h = disparity.height_px;
    std::vector<std::uint8_t> grey3;
    const std::uint8_t* rgb = rgb_of(left, w, h, grey3);
    const bool colour = rgb != nullptr;
    const std::size_t n = static_cast<std::size_t>(w) * h;
    // Each pixel's segment (-1: none), and each segment's pixel count to size its list.
    std::vector<std::int32_t> seg(n, -1);
    std::vector<Sums> sums(segments.size());
    for (std::size_t p = 0; p < n; ++p) {
        const std::int32_t cell = grid.pixel_cell[p];
        if (cell < 0) continue;
        const std::int32_t s = grid.cells[static_cast<std::size_t>(cell)].segment;
        if (s < 0 || !fresh[static_cast<std::size_t>(s)]) continue;
        seg[p] = s;
        ++sums[static_cast<std::size_t>(s)].n;
    }
    for (Sums& t : sums) t.disparities.reserve(t.n);
    const float* d = disparity.disparity_px.data();
    for (int v = 0; v < h; ++v) {
        const std::size_t row = static_cast<std::size_t>(v) * w;
        for (int u = 0; u < w; ++u) {
            const std::size_t p = row + u;
            const std::int32_t s = seg[p];
            if (s < 0) continue;
            Sums& t = sums[static_cast<std::size_t>(s)];
            t.u0 = std::min(t.u0, u), t.u1 = std::max(t.u1, u);
            t.v0 = std::min(t.v0, v), t.v1 = std::max(t.v1, v);
            t.disparities.push_back(d[p]);
            const bool right = u + 1 < w && seg[p + 1] == s;
            if (right) {
                ++t.pairs_h;
                t.rough_h += std::abs(d[p + 1] - d[p]) > kRoughStepPx;
            }
            if (v + 1 < h && seg[p + w] == s) {
                ++t.pairs_v;
                t.rough_v += std::abs(d[p + w] - d[p]) > kRoughStepPx;
            }
            if (!colour) continue;
            const std::uint8_t* px = &rgb[3 * p];
            const int level = px[0] + px[1] + px[2];
            ++t.coloured;
            for (int c = 0; c < 3; ++c) t.channel[c] += px[c];
            t.level += level;
            t.level2 += level * level;
            if (right) {
                t.grad += std::abs(px[3] + px[4] + px[5] - level);
                ++t.grad_pairs;
            }
        }
    }
    for (std::size_t s = 0; s < segments.size(); ++s) finish(sums[s], segments[s]);
}

}  // namespace cloud_analysis::geometry
