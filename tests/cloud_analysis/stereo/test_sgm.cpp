#include <catch2/catch.hpp>

#include <algorithm>
#include <cmath>
#include <random>
#include <vector>

#include "cloud_analysis/stereo/disparity.hpp"
#include "cloud_analysis/stereo/sgm.hpp"

using namespace cloud_analysis;

namespace {

struct Grey {
    int w = 0, h = 0;
    std::vector<std::uint8_t> px;
    int at(int x, int y) const {
        x = std::clamp(x, 0, w - 1);
        y = std::clamp(y, 0, h - 1);
        return px[static_cast<std::size_t>(y) * w + x];
    }
};

/// A random texture and its view shifted by `d` px (right(x - d) = left(x)), with per-pixel noise
/// of +-noise levels.
std::pair<Grey, Grey> shifted_pair(int w, int h, int d, int noise, unsigned seed) {
    std::mt19937 rng(seed);
    std::uniform_int_distribution<int> level(0, 255), jitter(-noise, noise);
    Grey left{w, h, std::vector<std::uint8_t>(static_cast<std::size_t>(w) * h)};
    Grey right = left;
    std::vector<int> texture(static_cast<std::size_t>(w + d) * h);
    for (auto& t : texture) t = level(rng);
    for (int y = 0; y < h; ++y) {
        for (int x = 0; x < w; ++x) {
            const std::size_t i = static_cast<std::size_t>(y) * w + x;
            const int base = texture[static_cast<std::size_t>(y) * (w + d) + x];
            left.px[i] = static_cast<std::uint8_t>(std::clamp(base + jitter(rng), 0, 255));
            const int moved = texture[static_cast<std::size_t>(y) * (w + d) + x + d];
            right.px[i] = static_cast<std::uint8_t>(std::clamp(moved + jitter(rng), 0, 255));
        }
    }
    return {left, right};
}

/// The matcher written out plainly from its definition (stereo/sgm.hpp): whole cost volume,
/// each path over it with Hirschmueller's recurrence, stripes primed by warm-up rows, winners
/// with cv::StereoSGBM's sub-pixel, uniqueness and disp12 rules.
std::vector<std::int16_t> reference_sgm(const Grey& l, const Grey& r, int first_column,
                                        const SgmRange& g, const SgmOptions& o) {
    const int w = l.w, h = l.h, nd = g.num_disparities, dmin = g.min_disparity;
    const auto census = [](const Grey& img, int x, int y) {
        std::uint32_t c = 0;
        int bit = 0;
        for (int dy = 0; dy <= 3; ++dy) {
            for (int dx = -4; dx <= 4; ++dx) {
                if (dy == 0 && dx <= 0) continue;
                if (img.at(x + dx, y + dy) > img.at(x - dx, y - dy)) c |= 1u << bit;
                ++bit;
            }
        }
        return c;
    };
    const int x0 = std::max(first_column, dmin + nd - 1);
    // Census Hamming distances summed over the window, rows clamped to the image and columns
    // to the matched ones.
    std::vector<std::uint32_t> census_l(static_cast<std::size_t>(w) * h), census_r = census_l;
    for (int y = 0; y < h; ++y) {
        for (int x = 0; x < w; ++x) {
            census_l[static_cast<std::size_t>(y) * w + x] = census(l, x, y);
            census_r[static_cast<std::size_t>(y) * w + x] = census(r, x, y);
        }
    }
    const int radius = o.window / 2;
    const auto cost = [&](int x, int y, int d) {
        int sum = 0;
        for (int dy = -radius; dy <= radius; ++dy) {
            for (int dx = -radius; dx <= radius; ++dx) {
                const int xx = std::clamp(x + dx, x0, w - 1);
                const std::size_t row = static_cast<std::size_t>(std::clamp(y + dy, 0, h - 1)) * w;
                sum += __builtin_popcount(census_l[row + xx] ^ census_r[row + xx - dmin - d]);
                const int yy = std::clamp(y + dy, 0, h - 1);
                sum += std::min(std::abs(l.at(xx, yy) - r.at(xx - dmin - d, yy)), o.intensity_cap);
            }
        }
        return sum;
    };
    const auto step = [&](const std::vector<int>& prev, int y, int x) {
        const int m = *std::min_element(prev.begin(), prev.end());
        std::vector<int> out(static_cast<std::size_t>(nd));
        for (int d = 0; d < nd; ++d) {
            int best = std::min(prev[d], m + o.p2);
            if (d > 0) best = std::min(best, prev[d - 1] + o.p1);
            if (d + 1 < nd) best = std::min(best, prev[d + 1] + o.p1);
            out[d] = cost(x, y, d) + best - m;
        }
        return out;
    };
    const std::int16_t invalid = static_cast<std::int16_t>((dmin - 1) * 16);
    std::vector<std::int16_t> out(static_cast<std::size_t>(w) * h, invalid);
    const int n = std::min(o.stripes, h);
    for (int s = 0; s < n; ++s) {
        const int y0 = s * h / n, y1 = (s + 1) * h / n;
        std::vector<std::vector<int>> top(static_cast<std::size_t>(w),
                                          std::vector<int>(static_cast<std::size_t>(nd), 0));
        for (int y = std::max(0, y0 - o.warmup_rows); y < y1; ++y) {
            for (int x = x0; x < w; ++x) top[x] = step(top[x], y, x);
            if (y < y0) continue;
            std::vector<std::vector<int>> sum(static_cast<std::size_t>(w));
            std::vector<int> lr(static_cast<std::size_t>(nd), 0), rl = lr;
            for (int x = x0; x < w; ++x) {
                lr = step(lr, y, x);
                sum[x] = top[x];
                for (int d = 0; d < nd; ++d) sum[x][d] += lr[d];
            }
            std::vector<int> right_cost(static_cast<std::size_t>(w), 1 << 30);
            std::vector<int> right_disp(static_cast<std::size_t>(w), -1);
            std::vector<int> disp(static_cast<std::size_t>(w), invalid);
            for (int x = w - 1; x >= x0; --x) {
                rl = step(rl, y, x);
                std::vector<int> sx = sum[x];
                for (int d = 0; d < nd; ++d) sx[d] += rl[d];
                const int best =
                    static_cast<int>(std::min_element(sx.begin(), sx.end()) - sx.begin());
                const int min_s = sx[best];
                bool unique = true;
                for (int d = 0; d < nd; ++d) {
                    if (sx[d] * (100 - g.uniqueness_ratio) < min_s * 100 &&
                        std::abs(d - best) > 1) {
                        unique = false;
                    }
                }
                if (!unique) continue;
                const int xr = x - best - dmin;
                if (right_cost[xr] > min_s) {
                    right_cost[xr] = min_s;
                    right_disp[xr] = best + dmin;
                }
                int d16 = best * 16;
                if (best > 0 && best < nd - 1 && o.subpixel == "parabola") {
                    const int denom2 = std::max(sx[best - 1] + sx[best + 1] - 2 * min_s, 1);
                    d16 += ((sx[best - 1] - sx[best + 1]) * 16 + denom2) / (denom2 * 2);
                } else if (best > 0 && best < nd - 1) {
                    const double below = sx[best - 1], above = sx[best + 1];
                    const double denom = 2.0 * (std::max(below, above) - min_s);
                    if (denom > 0) {
                        d16 += static_cast<int>(std::lround(16.0 * (below - above) / denom));
                    }
                }
                disp[x] = d16 + dmin * 16;
            }
            for (int x = 0; x < w; ++x) {
                const int d = disp[x];
                if (d == invalid || g.disp12_max_diff < 0) {
                    out[static_cast<std::size_t>(y) * w + x] = static_cast<std::int16_t>(d);
                    continue;
                }
                const int lo = d >> 4, hi = (d + 15) >> 4, xl = x - lo, xh = x - hi;
                const bool bad_lo = xl >= 0 && xl < w && right_disp[xl] >= 0 &&
                                    std::abs(right_disp[xl] - lo) > g.disp12_max_diff;
                const bool bad_hi = xh >= 0 && xh < w && right_disp[xh] >= 0 &&
                                    std::abs(right_disp[xh] - hi) > g.disp12_max_diff;
                out[static_cast<std::size_t>(y) * w + x] =
                    static_cast<std::int16_t>(bad_lo && bad_hi ? invalid : d);
            }
        }
    }
    return out;
}

std::vector<std::int16_t> run(const Grey& l, const Grey& r, int first_column, const SgmRange& g,
                              const SgmOptions& o) {
    std::vector<std::int16_t> out(static_cast<std::size_t>(l.w) * l.h, 12345);
    SgmMatcher(o).compute(l.px.data(), r.px.data(), static_cast<std::size_t>(l.w), l.w, l.h,
                          first_column, g, out.data(), static_cast<std::size_t>(l.w));
    return out;
}

}  // namespace

TEST_CASE("census SGM kernels equal the plain reference bit for bit on random pairs",
          "[disparity][sgm]") {
    std::vector<std::string> kernels = {"portable"};
    if (sgm_has_avx2()) kernels.push_back("avx2");
    struct Case {
        int w, h, shift, noise, first_column, min_d, nd, uniqueness, disp12, stripes, warmup,
            window, cap;
    };
    const Case cases[] = {
        {72, 30, 9, 20, 0, 0, 32, 0, 1, 1, 0, 1, 0},
        {72, 30, 9, 20, 32, 0, 32, 0, 1, 3, 4, 5, 8},
        {90, 26, 14, 40, 40, 5, 32, 15, -1, 2, 16, 3, 31},
        {60, 20, 3, 255, 0, 2, 16, 5, 0, 4, 2, 7, 0},
        {80, 24, 20, 10, 48, 0, 48, 0, 2, 2, 30, 5, 20},
        {40, 12, 5, 30, 36, 0, 16, 0, 1, 3, 1, 9, 4},
    };
    unsigned seed = 1;
    for (const Case& c : cases) {
        auto [left, right] = shifted_pair(c.w, c.h, c.shift, c.noise, seed++);
        SgmRange g;
        g.min_disparity = c.min_d;
        g.num_disparities = c.nd;
        g.uniqueness_ratio = c.uniqueness;
        g.disp12_max_diff = c.disp12;
        SgmOptions o;
        o.stripes = c.stripes;
        o.warmup_rows = c.warmup;
        o.window = c.window;
        o.intensity_cap = c.cap;
        o.p1 = (5 + c.shift % 4) * c.window;
        o.p2 = (40 + c.noise) * c.window * c.window;
        o.subpixel = seed % 2 == 0 ? "equiangular" : "parabola";
        const auto expected = reference_sgm(left, right, c.first_column, g, o);
        for (const auto& kernel : kernels) {
            INFO("kernel " << kernel << ", case " << seed - 1);
            o.kernel = kernel;
            CHECK(run(left, right, c.first_column, g, o) == expected);
        }
    }
}

TEST_CASE("census SGM finds the shift of a noisy random-dot pair", "[disparity][sgm]") {
    const int d = 17;
    auto [left, right] = shifted_pair(200, 90, d, 8, 42);
    SgmRange g;
    g.num_disparities = 48;
    const auto map = run(left, right, 0, g, SgmOptions{});
    std::size_t valid = 0, exact = 0;
    for (int y = 0; y < 90; ++y) {
        for (int x = 60; x < 200; ++x) {
            const int v = map[static_cast<std::size_t>(y) * 200 + x];
            if (v < 0) continue;
            ++valid;
            if (std::abs(v - d * 16) <= 4) ++exact;
        }
    }
    CHECK(valid > 90 * 140 * 95 / 100);
    CHECK(exact > valid * 98 / 100);
}

TEST_CASE("the sgm matcher behind DisparityMatcher keeps the padding and downscale contracts",
          "[disparity][sgm]") {
    const int d = 12;
    auto [l, r] = shifted_pair(160, 80, d, 4, 7);
    const ImageU8 left{160, 80, 1, l.px}, right{160, 80, 1, r.px};
    for (const int downscale : {1, 2}) {
        DisparityOptions options;
        options.matcher = "sgm";
        options.num_disparities = 32 * downscale;
        options.downscale = downscale;
        const DisparityMap map = compute_disparity(left, right, options);
        REQUIRE(map.width_px == 160);
        std::size_t valid = 0, close = 0;
        for (int v = 8; v < 72; ++v) {
            for (int u = 0; u < 156; ++u) {  // the border band included: padding
                const float got = map.disparity_px[static_cast<std::size_t>(v) * 160 + u];
                if (got <= 0.0f) continue;
                ++valid;
                if (std::abs(got - static_cast<float>(d)) <= 0.5f * downscale) ++close;
            }
        }
        INFO("downscale " << downscale);
        CHECK(valid > 64 * 156 * 85 / 100);
        CHECK(close > valid * 9 / 10);
    }
}

TEST_CASE("the sgm matcher refuses what it does not do, naming the field", "[disparity][sgm]") {
    DisparityOptions o;
    o.matcher = "elas";
    CHECK_THROWS_WITH(o.validate(), Catch::StartsWith("matcher"));
    o = {};
    o.matcher = "sgm";
    CHECK_NOTHROW(o.validate());
    o.colour = true;
    CHECK_THROWS_WITH(o.validate(), Catch::StartsWith("colour"));
    o = {};
    o.matcher = "sgm";
    o.wls = true;
    CHECK_THROWS_WITH(o.validate(), Catch::StartsWith("wls"));
    o = {};
    o.matcher = "sgm";
    o.sgm.p2 = o.sgm.p1;
    CHECK_THROWS_WITH(o.validate(), Catch::StartsWith("p2"));
    SgmOptions s;
    s.kernel = "neon";
    CHECK_THROWS_WITH(s.validate(), Catch::StartsWith("kernel"));
    s = {};
    s.window = 4;
    CHECK_THROWS_WITH(s.validate(), Catch::StartsWith("window"));
    s.window = 5;
    s.intensity_cap = 32;
    CHECK_THROWS_WITH(s.validate(), Catch::StartsWith("intensity_cap"));
    s.intensity_cap = 0;
    s.window = 9;
    s.p2 = 20000;  // three path sums of 31 * 81 + p2 would overflow 16 bits
    CHECK_THROWS_WITH(s.validate(), Catch::StartsWith("p2"));
}
