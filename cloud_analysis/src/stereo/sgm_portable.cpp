// Portable kernel of the census SGM row (sgm_row.hpp): plain loops, the bits the AVX2 kernel
// must reproduce, and the path on CPUs without AVX2.

#include <algorithm>
#include <cstdlib>
#include <cstring>

#include "sgm_row.hpp"

namespace cloud_analysis::sgm_detail {
namespace {

/// Box costs of pixel x into `c` (the row's cost buffer at x): from pixel x - 1's, which sit
/// just before it, unless x is the first matched column.
void box_costs(const SgmRow& r, int x, std::uint16_t* c) {
    const int nd = r.num_disparities;
    const int last = r.width - 1 - r.x_begin;
    const int i = x - r.x_begin;
    const auto column = [&](int j) {
        return r.column_sum + static_cast<std::size_t>(std::clamp(j, 0, last)) * nd;
    };
    if (i == 0) {
        std::fill(c, c + nd, std::uint16_t{0});
        for (int j = -r.radius; j <= r.radius; ++j) {
            const std::uint16_t* col = column(j);
            for (int d = 0; d < nd; ++d) c[d] = static_cast<std::uint16_t>(c[d] + col[d]);
        }
        return;
    }
    const std::uint16_t* before = c - nd;
    const std::uint16_t* enter = column(i + r.radius);
    const std::uint16_t* leave = column(i - r.radius - 1);
    for (int d = 0; d < nd; ++d) {
        c[d] = static_cast<std::uint16_t>(before[d] + enter[d] - leave[d]);
    }
}

/// One step along a path (Hirschmueller's recurrence, minus the previous minimum so the values
/// stay bounded by max cost + p2); returns the new minimum.
std::uint16_t path_step(const std::uint16_t* prev, int prev_min, const std::uint16_t* c, int nd,
                        int p1, int p2, std::uint16_t* out) {
    const int jump = prev_min + p2;
    int out_min = 0xFFFF;
    for (int d = 0; d < nd; ++d) {
        int best = prev[d];
        if (d > 0) best = std::min(best, prev[d - 1] + p1);
        if (d + 1 < nd) best = std::min(best, prev[d + 1] + p1);
        best = std::min(best, jump);
        const int v = c[d] + best - prev_min;
        out[d] = static_cast<std::uint16_t>(v);
        out_min = std::min(out_min, v);
    }
    return static_cast<std::uint16_t>(out_min);
}

/// The top-down path of pixel i, updated in place.
void top_step(const SgmRow& r, int i, const std::uint16_t* c) {
    const int nd = r.num_disparities;
    std::uint16_t next[kMaxDisparities];
    std::uint16_t* top = r.top + static_cast<std::size_t>(i) * nd;
    r.top_min[i] = path_step(top, r.top_min[i], c, nd, r.p1, r.p2, next);
    std::memcpy(top, next, sizeof(std::uint16_t) * static_cast<std::size_t>(nd));
}

/// Winner of the summed costs `s` at column x (cv::StereoSGBM's rules), written to the row.
void take_winner(const SgmRow& r, int x, const std::uint16_t* s) {
    const int nd = r.num_disparities;
    int best = 0;
    int min_s = s[0];
    for (int d = 1; d < nd; ++d) {
        if (s[d] < min_s) {
            min_s = s[d];
            best = d;
        }
    }
    if (r.uniqueness_ratio > 0) {
        for (int d = 0; d < nd; ++d) {
            if (s[d] * (100 - r.uniqueness_ratio) < min_s * 100 && std::abs(d - best) > 1) {
                r.disparity[x] = kInvalid;
                return;
            }
        }
    }
    const int xr = x - best - r.min_disparity;
    if (r.right_cost[xr] > min_s) {
        r.right_cost[xr] = static_cast<std::uint16_t>(min_s);
        r.right_disp[xr] = static_cast<std::int16_t>(best + r.min_disparity);
    }
    r.disparity[x] =
        static_cast<std::int16_t>(subpixel16(s, best, nd, r.equiangular) + r.min_disparity * 16);
}

}  // namespace

void window_row_portable(const SgmRow& r) {
    const int nd = r.num_disparities;
    for (int x = r.x_begin; x < r.width; ++x) {
        const std::size_t at = static_cast<std::size_t>(x - r.x_begin) * nd;
        const std::uint32_t left = r.census_left[x];
        const std::uint32_t* right = r.census_right_rev + (r.width - 1 - x + r.min_disparity);
        const int grey = r.grey_left[x];
        const std::uint8_t* grey_right = r.grey_right_rev + (r.width - 1 - x + r.min_disparity);
        for (int d = 0; d < nd; ++d) {
            const int c = __builtin_popcount(left ^ right[d]) +
                          std::min(std::abs(grey - grey_right[d]), r.intensity_cap);
            r.column_sum[at + d] =
                static_cast<std::uint16_t>(r.column_sum[at + d] + c - r.ring[at + d]);
            r.ring[at + d] = static_cast<std::uint8_t>(c);
        }
    }
}

void warmup_row_portable(const SgmRow& r) {
    const int nd = r.num_disparities;
    for (int x = r.x_begin; x < r.width; ++x) {
        const int i = x - r.x_begin;
        std::uint16_t* c = r.cost + static_cast<std::size_t>(i) * nd;
        box_costs(r, x, c);
        top_step(r, i, c);
    }
}

void match_row_portable(const SgmRow& r) {
    const int nd = r.num_disparities;
    std::uint16_t path_a[kMaxDisparities] = {};
    std::uint16_t path_b[kMaxDisparities];
    std::uint16_t* prev = path_a;
    std::uint16_t* cur = path_b;
    int prev_min = 0;
    for (int x = r.x_begin; x < r.width; ++x) {
        const int i = x - r.x_begin;
        const std::size_t at = static_cast<std::size_t>(i) * nd;
        std::uint16_t* c = r.cost + at;
        box_costs(r, x, c);
        prev_min = path_step(prev, prev_min, c, nd, r.p1, r.p2, cur);
        std::swap(prev, cur);
        top_step(r, i, c);
        for (int d = 0; d < nd; ++d) {
            r.sum[at + d] = static_cast<std::uint16_t>(prev[d] + r.top[at + d]);
        }
    }
    std::fill(r.right_cost, r.right_cost + r.width, std::uint16_t{0xFFFF});
    std::fill(r.right_disp, r.right_disp + r.width, std::int16_t{-1});
    std::fill(r.disparity, r.disparity + r.x_begin, kInvalid);
    std::fill(path_a, path_a + nd, std::uint16_t{0});
    prev = path_a;
    cur = path_b;
    prev_min = 0;
    std::uint16_t s[kMaxDisparities];
    for (int x = r.width - 1; x >= r.x_begin; --x) {
        const std::size_t at = static_cast<std::size_t>(x - r.x_begin) * nd;
        prev_min = path_step(prev, prev_min, r.cost + at, nd, r.p1, r.p2, cur);
        std::swap(prev, cur);
        for (int d = 0; d < nd; ++d) s[d] = static_cast<std::uint16_t>(r.sum[at + d] + prev[d]);
        take_winner(r, x, s);
    }
}

}  // namespace cloud_analysis::sgm_detail
