#pragma once

// One image row of the census SGM matcher (stereo/sgm.hpp), in a portable and an AVX2 kernel
// that give the same bits. Buffers are 32-byte aligned; per pixel they hold the
// num_disparities values of that pixel, pixels from x_begin on.
//
// The data term is the census Hamming distance summed over a window x window box. A stripe
// keeps the raw costs of the last `window` rows in a ring (8 bits a cell) and their column sums
// (`column_sum`): each new row adds the row entering the box and subtracts the one leaving
// it (window_row), and the path kernels slide the box along the row (the box sum of pixel x
// is that of x - 1 plus the column sum entering it minus the one leaving it). Rows are
// clamped to the image, columns to [x_begin, width).

#include <cstdint>

namespace cloud_analysis::sgm_detail {

inline constexpr int kMaxDisparities = 256;

struct SgmRow {
    const std::uint32_t* census_left = nullptr;       ///< census of the entering left row, by x
    const std::uint32_t* census_right_rev = nullptr;  ///< ... of the right row, by width-1-x
    const std::uint8_t* grey_left = nullptr;          ///< grey levels of the entering left row
    const std::uint8_t* grey_right_rev = nullptr;     ///< ... of the right row, by width-1-x
    int intensity_cap = 0;                            ///< cap of the intensity term, 0 = none
    std::uint8_t* ring = nullptr;         ///< raw costs of the leaving row; replaced in place
    std::uint16_t* column_sum = nullptr;  ///< raw costs summed over the window's rows
    int radius = 0;                       ///< half the window side, px
    int width = 0;                        ///< pixels in the row
    int x_begin = 0;                      ///< first matched column, >= min + num - 1
    int num_disparities = 0;              ///< multiple of 16
    int min_disparity = 0;                ///< >= 0
    std::uint16_t p1 = 0;                 ///< small-step penalty
    std::uint16_t p2 = 0;                 ///< large-step penalty
    std::uint16_t* cost = nullptr;        ///< scratch: box costs of the row
    std::uint16_t* sum = nullptr;         ///< scratch: left-to-right + top-down path costs
    std::uint16_t* top = nullptr;         ///< top-down path of the row above; updated in place
    std::uint16_t* top_min = nullptr;     ///< its minimum per pixel; updated in place
    int uniqueness_ratio = 0;             ///< %, 0 = off
    bool equiangular = false;  ///< sub-pixel step by equiangular lines instead of a parabola
    std::int16_t* disparity = nullptr;    ///< out: disparity * 16 from x_begin, or kInvalid
    std::uint16_t* right_cost = nullptr;  ///< out: best cost seen per right-view column
    std::int16_t* right_disp = nullptr;   ///< out: its disparity (px, -1 = none)
};

/// Marks a failed pixel in SgmRow::disparity (replaced by (min - 1) * 16 afterwards).
inline constexpr std::int16_t kInvalid = -32768;

/// Raw costs of the row entering the window into `ring`, column sums updated.
void window_row_portable(const SgmRow& row);
/// Box costs and the top-down path only (a warm-up row above a stripe).
void warmup_row_portable(const SgmRow& row);
/// The whole row: costs, three paths, winners, sub-pixel step, uniqueness, right-view winners.
void match_row_portable(const SgmRow& row);

void window_row_avx2(const SgmRow& row);
void warmup_row_avx2(const SgmRow& row);
void match_row_avx2(const SgmRow& row);

// In an unnamed namespace: every kernel file gets its own copy compiled for its own target, so
// the linker cannot hand the AVX2 file's copy to code that runs on any CPU.
namespace {

/// Sub-pixel disparity * 16 of index `best` from its neighbours' sums, without the
/// min_disparity offset: cv::StereoSGBM's parabola, or the equiangular fit (Shimizu & Okutomi,
/// "Sub-pixel estimation error cancellation on area-based matching", IJCV 2005) that suits
/// census costs.
inline int subpixel16(const std::uint16_t* s, int best, int num_disparities, bool equiangular) {
    if (best <= 0 || best >= num_disparities - 1) return best * 16;
    const int left = s[best - 1], right = s[best + 1], centre = s[best];
    if (equiangular) {
        const int denom = 2 * ((left > right ? left : right) - centre);
        if (denom <= 0) return best * 16;
        const int num = (left - right) * 16;
        return best * 16 + (num + (num >= 0 ? denom / 2 : -denom / 2)) / denom;
    }
    int denom2 = left + right - 2 * centre;
    if (denom2 < 1) denom2 = 1;
    return best * 16 + ((left - right) * 16 + denom2) / (denom2 * 2);
}

}  // namespace

}  // namespace cloud_analysis::sgm_detail
