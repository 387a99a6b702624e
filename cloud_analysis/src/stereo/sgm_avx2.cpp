// AVX2 kernel of the census SGM row (sgm_row.hpp): 16 disparities of 16 bits per register, the
// same bits as the portable kernel. This file alone is compiled with -mavx2 and is only called
// after a run-time check of the CPU; it uses no standard-library templates, whose instances
// the linker could share with code that must run on any CPU.

#include <immintrin.h>

#include "sgm_row.hpp"

namespace cloud_analysis::sgm_detail {
namespace {

/// Lane i <- cur[i - 1], lane 0 <- prev[15].
inline __m256i shift_in_prev(__m256i cur, __m256i prev) {
    return _mm256_alignr_epi8(cur, _mm256_permute2x128_si256(prev, cur, 0x21), 14);
}

/// Lane i <- cur[i + 1], lane 15 <- next[0].
inline __m256i shift_in_next(__m256i cur, __m256i next) {
    return _mm256_alignr_epi8(_mm256_permute2x128_si256(cur, next, 0x21), cur, 2);
}

inline std::uint16_t horizontal_min(__m256i v) {
    const __m128i m = _mm_min_epu16(_mm256_castsi256_si128(v), _mm256_extracti128_si256(v, 1));
    return static_cast<std::uint16_t>(_mm_extract_epi16(_mm_minpos_epu16(m), 0));
}

/// Hamming distances of one left census against 16 right ones (reversed layout).
inline __m256i costs16(const std::uint32_t* right, __m256i left) {
    const __m256i lut = _mm256_setr_epi8(0, 1, 1, 2, 1, 2, 2, 3, 1, 2, 2, 3, 2, 3, 3, 4, 0, 1, 1, 2,
                                         1, 2, 2, 3, 1, 2, 2, 3, 2, 3, 3, 4);
    const __m256i nibble = _mm256_set1_epi8(0x0F);
    const __m256i ones = _mm256_set1_epi8(1);
    const auto bytes = [&](__m256i v) {
        const __m256i lo = _mm256_and_si256(v, nibble);
        const __m256i hi = _mm256_and_si256(_mm256_srli_epi16(v, 4), nibble);
        const __m256i n =
            _mm256_add_epi8(_mm256_shuffle_epi8(lut, lo), _mm256_shuffle_epi8(lut, hi));
        return _mm256_maddubs_epi16(n, ones);  // counts per 16-bit half
    };
    const __m256i a =
        bytes(_mm256_xor_si256(_mm256_loadu_si256(reinterpret_cast<const __m256i*>(right)), left));
    const __m256i b = bytes(
        _mm256_xor_si256(_mm256_loadu_si256(reinterpret_cast<const __m256i*>(right + 8)), left));
    // Pairs of halves summed: [a0-3 b0-3 | a4-7 b4-7], then the quadwords put in order.
    return _mm256_permute4x64_epi64(_mm256_hadd_epi16(a, b), 0xD8);
}

/// One path step of 16 disparities: min(L(d), L(d +- 1) + p1, min L + p2) - min L + cost.
inline __m256i step16(__m256i before, __m256i cur, __m256i next, __m256i cost, __m256i p1,
                      __m256i jump, __m256i prev_min) {
    const __m256i neighbours =
        _mm256_min_epu16(shift_in_prev(cur, before), shift_in_next(cur, next));
    __m256i best = _mm256_min_epu16(_mm256_adds_epu16(neighbours, p1), cur);
    best = _mm256_min_epu16(best, jump);
    return _mm256_add_epi16(_mm256_sub_epi16(best, prev_min), cost);
}

inline __m256i load(const std::uint16_t* p) {
    return _mm256_load_si256(reinterpret_cast<const __m256i*>(p));
}
inline void store(std::uint16_t* p, __m256i v) {
    _mm256_store_si256(reinterpret_cast<__m256i*>(p), v);
}

/// A path running along the row: its previous pixel's values and minimum.
struct RowPath {
    alignas(32) std::uint16_t a[kMaxDisparities];
    alignas(32) std::uint16_t b[kMaxDisparities];
    std::uint16_t* prev = a;
    std::uint16_t* cur = b;
    std::uint16_t prev_min = 0;
    void reset(int nd) {
        for (int d = 0; d < nd; ++d) a[d] = 0;
        prev = a;
        cur = b;
        prev_min = 0;
    }
    void swap() {
        std::uint16_t* t = prev;
        prev = cur;
        cur = t;
    }
};

/// Column sums of matched column index j, clamped to the matched columns.
inline const std::uint16_t* column(const SgmRow& r, int j) {
    const int last = r.width - 1 - r.x_begin;
    const int at = j < 0 ? 0 : (j > last ? last : j);
    return r.column_sum + static_cast<std::size_t>(at) * r.num_disparities;
}

/// Box costs of the first matched column into the row's cost buffer.
inline void first_box(const SgmRow& r) {
    const int nv = r.num_disparities / 16;
    for (int k = 0; k < nv; ++k) {
        __m256i sum = _mm256_setzero_si256();
        for (int j = -r.radius; j <= r.radius; ++j) {
            sum = _mm256_add_epi16(sum, load(column(r, j) + 16 * k));
        }
        store(r.cost + 16 * k, sum);
    }
}

/// Box costs and top-down path of pixel x (and the left-to-right path and their sum unless
/// `lr` is null), one register of disparities at a time.
inline void forward_pixel(const SgmRow& r, int x, RowPath* lr) {
    const int nd = r.num_disparities;
    const int nv = nd / 16;
    const int i = x - r.x_begin;
    const std::size_t at = static_cast<std::size_t>(i) * nd;
    if (i == 0) first_box(r);
    const std::uint16_t* before = r.cost + at - (i == 0 ? 0 : nd);
    const std::uint16_t* enter = column(r, i + r.radius);
    const std::uint16_t* leave = column(r, i - r.radius - 1);
    const __m256i p1 = _mm256_set1_epi16(static_cast<short>(r.p1));
    const __m256i none = _mm256_set1_epi16(-1);
    std::uint16_t* top = r.top + at;
    const std::uint16_t top_min = r.top_min[x - r.x_begin];
    const __m256i top_minv = _mm256_set1_epi16(static_cast<short>(top_min));
    const __m256i top_jump = _mm256_set1_epi16(static_cast<short>(top_min + r.p2));
    __m256i top_before = none, top_cur = load(top), top_acc = none;
    const std::uint16_t lr_min = lr != nullptr ? lr->prev_min : 0;
    const __m256i lr_minv = _mm256_set1_epi16(static_cast<short>(lr_min));
    const __m256i lr_jump = _mm256_set1_epi16(static_cast<short>(lr_min + r.p2));
    __m256i lr_before = none, lr_cur = lr != nullptr ? load(lr->prev) : none, lr_acc = none;
    for (int k = 0; k < nv; ++k) {
        __m256i cost = load(before + 16 * k);
        if (i != 0) {
            cost = _mm256_sub_epi16(_mm256_add_epi16(cost, load(enter + 16 * k)),
                                    load(leave + 16 * k));
            store(r.cost + at + 16 * k, cost);
        }
        const __m256i top_next = k + 1 < nv ? load(top + 16 * (k + 1)) : none;
        const __m256i t = step16(top_before, top_cur, top_next, cost, p1, top_jump, top_minv);
        store(top + 16 * k, t);  // in place: slot k of the row above is no longer needed
        top_acc = _mm256_min_epu16(top_acc, t);
        top_before = top_cur;
        top_cur = top_next;
        if (lr == nullptr) continue;
        const __m256i lr_next = k + 1 < nv ? load(lr->prev + 16 * (k + 1)) : none;
        const __m256i l = step16(lr_before, lr_cur, lr_next, cost, p1, lr_jump, lr_minv);
        store(lr->cur + 16 * k, l);
        lr_acc = _mm256_min_epu16(lr_acc, l);
        lr_before = lr_cur;
        lr_cur = lr_next;
        store(r.sum + at + 16 * k, _mm256_add_epi16(l, t));
    }
    r.top_min[x - r.x_begin] = horizontal_min(top_acc);
    if (lr != nullptr) {
        lr->prev_min = horizontal_min(lr_acc);
        lr->swap();
    }
}

/// Whether a disparity other than best and its neighbours has s * (100 - ratio) < min * 100.
inline bool ambiguous(const std::uint16_t* s, int nv, int best, int min_s, int ratio) {
    if (ratio <= 0 || min_s == 0) return false;
    int threshold = (min_s * 100 - 1) / (100 - ratio);
    if (threshold > 0xFFFF) threshold = 0xFFFF;
    const __m256i thr = _mm256_set1_epi16(static_cast<short>(threshold));
    for (int k = 0; k < nv; ++k) {
        const __m256i v = load(s + 16 * k);
        unsigned mask = static_cast<unsigned>(
            _mm256_movemask_epi8(_mm256_cmpeq_epi16(_mm256_min_epu16(v, thr), v)));
        for (int d = best - 1; d <= best + 1; ++d) {
            const int lane = d - 16 * k;
            if (lane >= 0 && lane < 16) mask &= ~(3u << (2 * lane));
        }
        if (mask != 0) return true;
    }
    return false;
}

/// Right-to-left path of pixel x, the summed costs and the winner.
inline void backward_pixel(const SgmRow& r, int x, RowPath& rl) {
    const int nd = r.num_disparities;
    const int nv = nd / 16;
    const std::size_t at = static_cast<std::size_t>(x - r.x_begin) * nd;
    const __m256i p1 = _mm256_set1_epi16(static_cast<short>(r.p1));
    const __m256i none = _mm256_set1_epi16(-1);
    const __m256i minv = _mm256_set1_epi16(static_cast<short>(rl.prev_min));
    const __m256i jump = _mm256_set1_epi16(static_cast<short>(rl.prev_min + r.p2));
    alignas(32) std::uint16_t s[kMaxDisparities];
    __m256i before = none, cur = load(rl.prev), acc = none, s_acc = none;
    for (int k = 0; k < nv; ++k) {
        const __m256i next = k + 1 < nv ? load(rl.prev + 16 * (k + 1)) : none;
        const __m256i l = step16(before, cur, next, load(r.cost + at + 16 * k), p1, jump, minv);
        store(rl.cur + 16 * k, l);
        acc = _mm256_min_epu16(acc, l);
        const __m256i sum = _mm256_add_epi16(load(r.sum + at + 16 * k), l);
        store(s + 16 * k, sum);
        s_acc = _mm256_min_epu16(s_acc, sum);
        before = cur;
        cur = next;
    }
    rl.prev_min = horizontal_min(acc);
    rl.swap();
    const int min_s = horizontal_min(s_acc);
    const __m256i min_sv = _mm256_set1_epi16(static_cast<short>(min_s));
    int best = 0;
    for (int k = 0; k < nv; ++k) {
        const unsigned mask = static_cast<unsigned>(
            _mm256_movemask_epi8(_mm256_cmpeq_epi16(load(s + 16 * k), min_sv)));
        if (mask != 0) {
            best = 16 * k + __builtin_ctz(mask) / 2;
            break;
        }
    }
    if (ambiguous(s, nv, best, min_s, r.uniqueness_ratio)) {
        r.disparity[x] = kInvalid;
        return;
    }
    const int xr = x - best - r.min_disparity;
    if (r.right_cost[xr] > min_s) {
        r.right_cost[xr] = static_cast<std::uint16_t>(min_s);
        r.right_disp[xr] = static_cast<std::int16_t>(best + r.min_disparity);
    }
    r.disparity[x] =
        static_cast<std::int16_t>(subpixel16(s, best, nd, r.equiangular) + r.min_disparity * 16);
}

/// Raw costs of the entering row into the ring and the column sums, with or without the
/// intensity term (a cap of 0 adds nothing: the census-only loop skips it).
template <bool kIntensity>
void window_row(const SgmRow& r) {
    const int nv = r.num_disparities / 16;
    const __m256i cap = _mm256_set1_epi16(static_cast<short>(r.intensity_cap));
    for (int x = r.x_begin; x < r.width; ++x) {
        const std::size_t at = static_cast<std::size_t>(x - r.x_begin) * r.num_disparities;
        const __m256i left = _mm256_set1_epi32(static_cast<int>(r.census_left[x]));
        const std::uint32_t* right = r.census_right_rev + (r.width - 1 - x + r.min_disparity);
        const __m256i grey = _mm256_set1_epi16(static_cast<short>(r.grey_left[x]));
        const std::uint8_t* grey_right = r.grey_right_rev + (r.width - 1 - x + r.min_disparity);
        for (int k = 0; k < nv; ++k) {
            __m256i cost = costs16(right + 16 * k, left);
            if (kIntensity) {
                const __m256i other = _mm256_cvtepu8_epi16(
                    _mm_loadu_si128(reinterpret_cast<const __m128i*>(grey_right + 16 * k)));
                cost = _mm256_add_epi16(
                    cost, _mm256_min_epi16(_mm256_abs_epi16(_mm256_sub_epi16(grey, other)), cap));
            }
            __m128i* slot = reinterpret_cast<__m128i*>(r.ring + at + 16 * k);
            const __m256i leaving = _mm256_cvtepu8_epi16(_mm_load_si128(slot));
            std::uint16_t* sum = r.column_sum + at + 16 * k;
            store(sum, _mm256_sub_epi16(_mm256_add_epi16(load(sum), cost), leaving));
            _mm_store_si128(slot, _mm_packus_epi16(_mm256_castsi256_si128(cost),
                                                   _mm256_extracti128_si256(cost, 1)));
        }
    }
}

}  // namespace

void window_row_avx2(const SgmRow& r) {
    if (r.intensity_cap > 0) {
        window_row<true>(r);
    } else {
        window_row<false>(r);
    }
}

void warmup_row_avx2(const SgmRow& r) {
    for (int x = r.x_begin; x < r.width; ++x) forward_pixel(r, x, nullptr);
}

void match_row_avx2(const SgmRow& r) {
    RowPath path;
    path.reset(r.num_disparities);
    for (int x = r.x_begin; x < r.width; ++x) forward_pixel(r, x, &path);
    for (int x = 0; x < r.width; ++x) {
        r.right_cost[x] = 0xFFFF;
        r.right_disp[x] = -1;
    }
    for (int x = 0; x < r.x_begin; ++x) r.disparity[x] = kInvalid;
    path.reset(r.num_disparities);
    for (int x = r.width - 1; x >= r.x_begin; --x) backward_pixel(r, x, path);
}

}  // namespace cloud_analysis::sgm_detail
