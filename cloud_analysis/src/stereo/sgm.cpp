#include "cloud_analysis/stereo/sgm.hpp"

#include <algorithm>
#include <cstdlib>
#include <stdexcept>
#include <vector>

#include <opencv2/core.hpp>

#if defined(__SSE2__)
#include <emmintrin.h>
#endif

#include "sgm_row.hpp"

namespace cloud_analysis {
namespace {

using sgm_detail::kInvalid;
using sgm_detail::kMaxDisparities;
using sgm_detail::SgmRow;

[[noreturn]] void bad(const std::string& field, const std::string& rule) {
    throw std::invalid_argument(field + ": " + rule);
}

/// A 32-byte aligned array that only grows (kept across frames).
template <typename T>
class AlignedArray {
  public:
    T* data() { return data_.get(); }
    void reserve(std::size_t n) {
        if (n <= size_) return;
        const std::size_t bytes = (n * sizeof(T) + 31) / 32 * 32;
        data_.reset(static_cast<T*>(std::aligned_alloc(32, bytes)));
        if (!data_) throw std::bad_alloc();
        size_ = n;
    }

  private:
    struct Free {
        void operator()(T* p) const { std::free(p); }
    };
    std::unique_ptr<T, Free> data_;
    std::size_t size_ = 0;
};

/// Centre-symmetric census over 9x7: bit k of the 31 is I(p + o_k) > I(p - o_k) for the offsets
/// o_k of one half of the window; coordinates clamped at the borders. The bits are gathered in
/// four byte planes (8 comparisons each: byte lanes vectorise) and joined at the end;
/// `reversed` stores the row from right to left (the layout the cost loops read contiguously).
void census_row(const std::uint8_t* img, std::size_t stride, int w, int h, int y,
                std::uint8_t* planes, std::uint32_t* out, bool reversed) {
    std::fill(planes, planes + 4 * static_cast<std::size_t>(w), std::uint8_t{0});
    int bit = 0;
    for (int dy = 0; dy <= 3; ++dy) {
        const std::uint8_t* a = img + static_cast<std::size_t>(std::min(y + dy, h - 1)) * stride;
        const std::uint8_t* b = img + static_cast<std::size_t>(std::max(y - dy, 0)) * stride;
        for (int dx = -4; dx <= 4; ++dx) {
            if (dy == 0 && dx <= 0) continue;
            std::uint8_t* plane = planes + static_cast<std::size_t>(bit >> 3) * w;
            const std::uint8_t value = static_cast<std::uint8_t>(1u << (bit & 7));
            const int lo = std::min(std::abs(dx), w);
            const int hi = std::max(lo, w - std::abs(dx));
            const std::uint8_t* ap = a + dx;
            const std::uint8_t* bp = b - dx;
            int x = lo;
#if defined(__SSE2__)
            // Unsigned bytes compared as signed after flipping the top bit; 16 pixels a step.
            const __m128i flip = _mm_set1_epi8(static_cast<char>(0x80));
            const __m128i bitv = _mm_set1_epi8(static_cast<char>(value));
            for (; x + 16 <= hi; x += 16) {
                const __m128i av = _mm_loadu_si128(reinterpret_cast<const __m128i*>(ap + x));
                const __m128i bv = _mm_loadu_si128(reinterpret_cast<const __m128i*>(bp + x));
                const __m128i gt = _mm_cmpgt_epi8(_mm_xor_si128(av, flip), _mm_xor_si128(bv, flip));
                __m128i* dst = reinterpret_cast<__m128i*>(plane + x);
                _mm_storeu_si128(dst, _mm_or_si128(_mm_loadu_si128(dst), _mm_and_si128(gt, bitv)));
            }
#endif
            for (; x < hi; ++x) {
                plane[x] = static_cast<std::uint8_t>(plane[x] | (ap[x] > bp[x] ? value : 0));
            }
            const auto border = [&](int from, int to) {  // clamped coordinates
                for (int u = from; u < to; ++u) {
                    const int ua = std::clamp(u + dx, 0, w - 1);
                    const int ub = std::clamp(u - dx, 0, w - 1);
                    if (a[ua] > b[ub]) plane[u] = static_cast<std::uint8_t>(plane[u] | value);
                }
            };
            border(0, lo);
            border(hi, w);
            ++bit;
        }
    }
    const std::uint8_t* p0 = planes;
    const std::uint8_t* p1 = planes + w;
    const std::uint8_t* p2 = planes + 2 * static_cast<std::size_t>(w);
    const std::uint8_t* p3 = planes + 3 * static_cast<std::size_t>(w);
    for (int x = 0; x < w; ++x) {
        const std::uint32_t c = p0[x] | static_cast<std::uint32_t>(p1[x]) << 8 |
                                static_cast<std::uint32_t>(p2[x]) << 16 |
                                static_cast<std::uint32_t>(p3[x]) << 24;
        out[reversed ? w - 1 - x : x] = c;
    }
}

/// Throws std::invalid_argument unless `range` and the image size suit the sgm matcher.
void check_range(const SgmRange& range, int width, int height) {
    if (range.min_disparity < 0) bad("min_disparity", "must be >= 0 for the sgm matcher");
    if (range.num_disparities < 16 || range.num_disparities % 16 != 0 ||
        range.num_disparities > kMaxDisparities) {
        bad("num_disparities", "must be a multiple of 16, 16..256 for the sgm matcher");
    }
    if (range.uniqueness_ratio < 0 || range.uniqueness_ratio > 99) {
        bad("uniqueness_ratio", "must be 0..99");
    }
    if (width <= 0 || height <= 0) bad("images", "must not be empty");
}

/// Sets every pixel of the `width` x `height` map `out` to `value`.
void fill_map(std::int16_t* out, std::size_t out_stride, int width, int height,
              std::int16_t value) {
    for (int y = 0; y < height; ++y) {
        std::fill(out + static_cast<std::size_t>(y) * out_stride,
                  out + static_cast<std::size_t>(y) * out_stride + width, value);
    }
}

}  // namespace

bool sgm_has_avx2() {
#if defined(__x86_64__) || defined(__i386__)
    return __builtin_cpu_supports("avx2");
#else
    return false;
#endif
}

void SgmOptions::validate() const {
    if (p1 < 1) bad("p1", "must be >= 1");
    if (p2 <= p1) bad("p2", "must be > p1");
    if (window < 1 || window > 9 || window % 2 == 0) bad("window", "must be odd, 1..9");
    if (intensity_cap < 0 || intensity_cap > 31) bad("intensity_cap", "must be 0..31");
    if (3 * ((31 + intensity_cap) * window * window + p2) > 0xFFFF) {
        bad("p2", "must be <= 21845 - (31 + intensity_cap) * window^2 (16-bit path sums)");
    }
    if (stripes < 1) bad("stripes", "must be >= 1");
    if (warmup_rows < 0) bad("warmup_rows", "must be >= 0");
    if (subpixel != "parabola" && subpixel != "equiangular") {
        bad("subpixel", "must be parabola or equiangular");
    }
    if (kernel != "auto" && kernel != "avx2" && kernel != "portable") {
        bad("kernel", "must be auto, avx2 or portable");
    }
    if (kernel == "avx2" && !sgm_has_avx2()) bad("kernel", "this CPU has no AVX2");
}

/// Per-stripe working rows: a stripe runs on one thread at a time.
struct StripeBuffers {
    AlignedArray<std::uint8_t> ring;
    AlignedArray<std::uint16_t> cost, sum, top, top_min, right_cost, column_sum;
    AlignedArray<std::int16_t> disparity, right_disp;
};

struct SgmMatcher::Impl {
    SgmOptions options;
    bool avx2 = false;
    std::vector<std::uint32_t> census_left, census_right_rev;
    std::vector<std::uint8_t> grey_right_rev;  // the right view, rows reversed
    const std::uint8_t* grey_left = nullptr;   // the left view of the current call
    std::size_t grey_stride = 0;               // its row stride, bytes
    std::vector<StripeBuffers> stripes;
    std::size_t cells = 0;

    /// The census of both views and the right view's grey rows reversed (rows in parallel);
    /// the left view kept for the call.
    void census_views(const std::uint8_t* left, const std::uint8_t* right, std::size_t stride,
                      int width, int height);
    /// The row kernels' settings on stripe s's working rows, reserved for rows `width` pixels
    /// wide of which `pixels` are matched (`volume` cost cells).
    SgmRow stripe_row(std::size_t s, int width, int x_begin, const SgmRange& range,
                      std::size_t pixels, std::size_t volume);
    void match_stripe(SgmRow row, int height, int y0, int y1, int warm_from, const SgmRange& range,
                      std::int16_t* out, std::size_t out_stride) const;
};

SgmMatcher::SgmMatcher(const SgmOptions& options) : impl_(std::make_unique<Impl>()) {
    options.validate();
    impl_->options = options;
    impl_->avx2 = options.kernel == "avx2" || (options.kernel == "auto" && sgm_has_avx2());
}

SgmMatcher::~SgmMatcher() = default;
SgmMatcher::SgmMatcher(SgmMatcher&&) noexcept = default;
SgmMatcher& SgmMatcher::operator=(SgmMatcher&&) noexcept = default;

std::size_t SgmMatcher::last_cells() const { return impl_->cells; }

void SgmMatcher::Impl::match_stripe(SgmRow row, int height, int y0, int y1, int warm_from,
                                    const SgmRange& range, std::int16_t* out,
                                    std::size_t out_stride) const {
    const int w = row.width;
    const std::size_t pixels = static_cast<std::size_t>(w - row.x_begin);
    const std::size_t volume = pixels * static_cast<std::size_t>(row.num_disparities);
    std::fill(row.top, row.top + volume, std::uint16_t{0});  // a path starts at its cost
    std::fill(row.top_min, row.top_min + pixels, std::uint16_t{0});
    const int rows = 2 * row.radius + 1;  // the window's rows, in a ring
    std::uint8_t* const ring = row.ring;
    std::fill(ring, ring + volume * static_cast<std::size_t>(rows), std::uint8_t{0});
    std::fill(row.column_sum, row.column_sum + volume, std::uint16_t{0});
    const auto window = avx2 ? sgm_detail::window_row_avx2 : sgm_detail::window_row_portable;
    const auto warmup = avx2 ? sgm_detail::warmup_row_avx2 : sgm_detail::warmup_row_portable;
    const auto match = avx2 ? sgm_detail::match_row_avx2 : sgm_detail::match_row_portable;
    // Row t enters the window (clamped to the image) in ring slot t mod rows, replacing row
    // t - rows: the slots start at zero, so the first rows - 1 rows only add.
    const auto enter = [&](int t) {
        const std::size_t yc = static_cast<std::size_t>(std::clamp(t, 0, height - 1));
        row.census_left = census_left.data() + yc * w;
        row.census_right_rev = census_right_rev.data() + yc * w;
        row.grey_left = grey_left + yc * grey_stride;
        row.grey_right_rev = grey_right_rev.data() + yc * w;
        row.ring = ring + static_cast<std::size_t>((t % rows + rows) % rows) * volume;
        window(row);
    };
    for (int t = warm_from - row.radius; t < warm_from + row.radius; ++t) enter(t);
    const std::int16_t invalid = static_cast<std::int16_t>((range.min_disparity - 1) * 16);
    for (int y = warm_from; y < y1; ++y) {
        enter(y + row.radius);
        if (y < y0) {
            warmup(row);
            continue;
        }
        match(row);
        // Left-right check against the right view's winners (cv::StereoSGBM's disp12MaxDiff:
        // a pixel fails when both neighbouring integer disparities disagree).
        std::int16_t* dst = out + static_cast<std::size_t>(y) * out_stride;
        const std::int16_t* right = row.right_disp;
        const int max_diff = range.disp12_max_diff;
        for (int x = 0; x < w; ++x) {
            const int d = row.disparity[x];
            if (d == kInvalid) {
                dst[x] = invalid;
                continue;
            }
            dst[x] = static_cast<std::int16_t>(d);
            if (max_diff < 0) continue;
            const int d_lo = d >> 4, d_hi = (d + 15) >> 4;
            const int x_lo = x - d_lo, x_hi = x - d_hi;
            if (x_lo >= 0 && x_lo < w && right[x_lo] >= 0 &&
                std::abs(right[x_lo] - d_lo) > max_diff && x_hi >= 0 && x_hi < w &&
                right[x_hi] >= 0 && std::abs(right[x_hi] - d_hi) > max_diff) {
                dst[x] = invalid;
            }
        }
    }
}

void SgmMatcher::Impl::census_views(const std::uint8_t* left, const std::uint8_t* right,
                                    std::size_t stride, int width, int height) {
    const std::size_t plane = static_cast<std::size_t>(width) * height;
    census_left.resize(plane);
    census_right_rev.resize(plane);
    grey_right_rev.resize(plane);
    grey_left = left;
    grey_stride = stride;
    cv::parallel_for_(cv::Range(0, height), [&](const cv::Range& rows) {
        std::vector<std::uint8_t> planes(4 * static_cast<std::size_t>(width));
        for (int y = rows.start; y < rows.end; ++y) {
            const std::size_t at = static_cast<std::size_t>(y) * width;
            census_row(left, stride, width, height, y, planes.data(), census_left.data() + at,
                       false);
            census_row(right, stride, width, height, y, planes.data(), census_right_rev.data() + at,
                       true);
            std::reverse_copy(right + static_cast<std::size_t>(y) * stride,
                              right + static_cast<std::size_t>(y) * stride + width,
                              grey_right_rev.data() + at);
        }
    });
}

SgmRow SgmMatcher::Impl::stripe_row(std::size_t s, int width, int x_begin, const SgmRange& range,
                                    std::size_t pixels, std::size_t volume) {
    StripeBuffers& b = stripes[s];
    b.ring.reserve(volume * static_cast<std::size_t>(options.window));
    b.column_sum.reserve(volume);
    b.cost.reserve(volume);
    b.sum.reserve(volume);
    b.top.reserve(volume);
    b.top_min.reserve(pixels);
    b.right_cost.reserve(static_cast<std::size_t>(width));
    b.disparity.reserve(static_cast<std::size_t>(width));
    b.right_disp.reserve(static_cast<std::size_t>(width));
    SgmRow row;
    row.width = width;
    row.x_begin = x_begin;
    row.num_disparities = range.num_disparities;
    row.min_disparity = range.min_disparity;
    row.p1 = static_cast<std::uint16_t>(options.p1);
    row.p2 = static_cast<std::uint16_t>(options.p2);
    row.ring = b.ring.data();
    row.column_sum = b.column_sum.data();
    row.radius = options.window / 2;
    row.intensity_cap = options.intensity_cap;
    row.cost = b.cost.data();
    row.sum = b.sum.data();
    row.top = b.top.data();
    row.top_min = b.top_min.data();
    row.uniqueness_ratio = range.uniqueness_ratio;
    row.equiangular = options.subpixel == "equiangular";
    row.disparity = b.disparity.data();
    row.right_cost = b.right_cost.data();
    row.right_disp = b.right_disp.data();
    return row;
}

void SgmMatcher::compute(const std::uint8_t* left, const std::uint8_t* right, std::size_t stride,
                         int width, int height, int first_column, const SgmRange& range,
                         std::int16_t* out, std::size_t out_stride) {
    Impl& m = *impl_;
    check_range(range, width, height);
    const std::int16_t invalid = static_cast<std::int16_t>((range.min_disparity - 1) * 16);
    const int nd = range.num_disparities;
    const int x_begin = std::max(first_column, range.min_disparity + nd - 1);
    m.cells = 0;
    if (x_begin >= width) {
        fill_map(out, out_stride, width, height, invalid);
        return;
    }
    m.census_views(left, right, stride, width, height);

    const int n = std::min(m.options.stripes, height);
    if (static_cast<int>(m.stripes.size()) < n) m.stripes.resize(static_cast<std::size_t>(n));
    const std::size_t pixels = static_cast<std::size_t>(width - x_begin);
    const std::size_t volume = pixels * static_cast<std::size_t>(nd);
    for (int s = 0; s < n; ++s) {
        const int y0 = s * height / n, y1 = (s + 1) * height / n;
        m.cells += static_cast<std::size_t>(y1 - std::max(0, y0 - m.options.warmup_rows)) * volume;
    }
    cv::parallel_for_(cv::Range(0, n), [&](const cv::Range& which) {
        for (int s = which.start; s < which.end; ++s) {
            const SgmRow row =
                m.stripe_row(static_cast<std::size_t>(s), width, x_begin, range, pixels, volume);
            const int y0 = s * height / n, y1 = (s + 1) * height / n;
            m.match_stripe(row, height, y0, y1, std::max(0, y0 - m.options.warmup_rows), range, out,
                           out_stride);
        }
    });
}

}  // namespace cloud_analysis
