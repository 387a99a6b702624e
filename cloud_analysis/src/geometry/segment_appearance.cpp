// What the segment classifier reads beside the rules' measurements: each segment's colour,
// texture and surface roughness, gathered in one pass over its pixels.
#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstdint>
#include <vector>

#include "cloud_analysis/support/task_queue.hpp"
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
    grey3.clear();
    grey3.reserve(left.data.size() * 3);
    for (const std::uint8_t g : left.data) grey3.insert(grey3.end(), 3, g);
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

/// Adds `band`'s sums of one segment to `into`: counts and integer sums add, the image box
/// grows, the disparities follow (bands in row order keep the one-pass order).
void merge(Sums& into, const Sums& band) {
    into.n += band.n;
    into.coloured += band.coloured;
    into.u0 = std::min(into.u0, band.u0), into.u1 = std::max(into.u1, band.u1);
    into.v0 = std::min(into.v0, band.v0), into.v1 = std::max(into.v1, band.v1);
    for (int c = 0; c < 3; ++c) into.channel[c] += band.channel[c];
    into.level += band.level, into.level2 += band.level2, into.grad += band.grad;
    into.grad_pairs += band.grad_pairs;
    into.pairs_h += band.pairs_h, into.rough_h += band.rough_h;
    into.pairs_v += band.pairs_v, into.rough_v += band.rough_v;
    into.disparities.insert(into.disparities.end(), band.disparities.begin(),
                            band.disparities.end());
}

/// One band of rows [v_begin, v_end): each pixel's segment (-1: none) into `seg`, and the
/// segments' pixel counts into `sums`.
void assign_rows(const Grid& grid, const std::vector<char>& fresh, int w, ColumnRange columns,
                 int v_begin, int v_end, std::vector<std::int32_t>& seg, std::vector<Sums>& sums) {
    for (int v = v_begin; v < v_end; ++v) {
        const std::size_t row = static_cast<std::size_t>(v) * static_cast<std::size_t>(w);
        for (int u = columns.u_begin; u < columns.u_end; ++u) {
            const std::size_t p = row + static_cast<std::size_t>(u);
            const std::int32_t cell = grid.pixel_cell[p];
            if (cell < 0) continue;
            const std::int32_t s = grid.cells[static_cast<std::size_t>(cell)].segment;
            if (s < 0 || !fresh[static_cast<std::size_t>(s)]) continue;
            seg[p] = s;
            ++sums[static_cast<std::size_t>(s)].n;
        }
    }
}

/// One band of rows [v_begin, v_end) summed into `sums`, whose pixel counts assign_rows made (a
/// pixel's pair below may lie in the next band: `seg` is whole when this runs).
void sum_rows(const std::vector<std::int32_t>& seg, const float* d, const std::uint8_t* rgb, int w,
              int h, ColumnRange columns, int v_begin, int v_end, std::vector<Sums>& sums) {
    for (Sums& t : sums) t.disparities.reserve(t.n);
    for (int v = v_begin; v < v_end; ++v) {
        const std::size_t row = static_cast<std::size_t>(v) * w;
        for (int u = columns.u_begin; u < columns.u_end; ++u) {
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
            if (rgb == nullptr) continue;
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
}

}  // namespace

void measure_appearance(const Grid& grid, const DisparityMap& disparity, const ImageU8& left,
                        const std::vector<char>& fresh, ColumnRange columns,
                        std::vector<Segment>& segments, int threads) {
    const int w = disparity.width_px, h = disparity.height_px;
    std::vector<std::uint8_t> grey3;
    const std::uint8_t* rgb = rgb_of(left, w, h, grey3);
    // Bands of rows on `threads` threads, each with sums of its own, merged in row order: the
    // same values as one pass.
    const std::size_t bands = row_bands(h, threads);
    std::vector<std::int32_t> seg(static_cast<std::size_t>(w) * h, -1);
    std::vector<std::vector<Sums>> band_sums(bands, std::vector<Sums>(segments.size()));
    for_each_chunk(static_cast<std::size_t>(h), bands,
                   [&](std::size_t k, std::size_t first, std::size_t last) {
                       assign_rows(grid, fresh, w, columns, static_cast<int>(first),
                                   static_cast<int>(last), seg, band_sums[k]);
                   });
    const float* d = disparity.disparity_px.data();
    for_each_chunk(static_cast<std::size_t>(h), bands,
                   [&](std::size_t k, std::size_t first, std::size_t last) {
                       sum_rows(seg, d, rgb, w, h, columns, static_cast<int>(first),
                                static_cast<int>(last), band_sums[k]);
                   });
    // Each segment merged and finished on its own (its quantiles cost as much as the pass),
    // taken in turn by the threads.
    std::atomic<std::size_t> next{0};
    for_each_chunk(bands, bands, [&](std::size_t, std::size_t, std::size_t) {
        for (std::size_t s = next++; s < segments.size(); s = next++) {
            for (std::size_t k = 1; k < bands; ++k) merge(band_sums[0][s], band_sums[k][s]);
            finish(band_sums[0][s], segments[s]);
        }
    });
}

}  // namespace cloud_analysis::geometry
