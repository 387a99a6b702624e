#include "cloud_analysis/support/select.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <stdexcept>

namespace cloud_analysis {
namespace {

// Below this, std::nth_element on the whole array is as fast as narrowing it.
constexpr std::size_t kNarrowFrom = 8192;
constexpr std::size_t kSample = 512;

/// Values [lo, hi] that hold rank k of n with near certainty: the sample's order statistics
/// about 4 standard deviations either side of where rank k falls in it (sample is sorted).
std::pair<double, double> bracket_of(const std::array<double, kSample>& sample, std::size_t k,
                                     std::size_t n) {
    const double p = static_cast<double>(k) / static_cast<double>(n);
    const double at = p * kSample;
    const double margin = 4.0 * std::sqrt(kSample * p * (1.0 - p)) + 3.0;
    const double inf = std::numeric_limits<double>::infinity();
    const auto lo_rank = static_cast<std::ptrdiff_t>(std::floor(at - margin));
    const auto hi_rank = static_cast<std::ptrdiff_t>(std::ceil(at + margin));
    return {lo_rank < 0 ? -inf : sample[static_cast<std::size_t>(lo_rank)],
            hi_rank >= static_cast<std::ptrdiff_t>(kSample)
                ? inf
                : sample[static_cast<std::size_t>(hi_rank)]};
}

/// Rank k of `values` from the values in its bracket (`below` of the values lie under it), or
/// from all of them when the bracket misses.
double select_in(std::vector<double>& bracket, std::size_t below, std::vector<double>& values,
                 std::size_t k) {
    if (k >= below && k - below < bracket.size()) {
        const auto j = static_cast<std::ptrdiff_t>(k - below);
        std::nth_element(bracket.begin(), bracket.begin() + j, bracket.end());
        return bracket[static_cast<std::size_t>(j)];
    }
    std::nth_element(values.begin(), values.begin() + static_cast<std::ptrdiff_t>(k), values.end());
    return values[k];
}

}  // namespace

std::pair<double, double> select_two(std::vector<double>& values, std::size_t k_lo,
                                     std::size_t k_hi) {
    const std::size_t n = values.size();
    if (k_lo > k_hi || k_hi >= n) throw std::invalid_argument("select_two: ranks out of order");
    const auto at = [&values](std::size_t i) {
        return values.begin() + static_cast<std::ptrdiff_t>(i);
    };
    if (n < kNarrowFrom) {
        std::nth_element(values.begin(), at(k_hi), values.end());
        const double hi = values[k_hi];
        if (k_lo == k_hi) return {hi, hi};
        // Everything before position k_hi is now <= values[k_hi], so rank k_lo lies there.
        std::nth_element(values.begin(), at(k_lo), at(k_hi));
        return {values[k_lo], hi};
    }
    std::array<double, kSample> sample{};
    const std::size_t stride = n / kSample;
    for (std::size_t i = 0; i < kSample; ++i) sample[i] = values[i * stride + stride / 2];
    std::sort(sample.begin(), sample.end());
    const auto [lo_min, lo_max] = bracket_of(sample, k_lo, n);
    const auto [hi_min, hi_max] = bracket_of(sample, k_hi, n);
    const bool two = k_lo != k_hi;
    std::size_t below_lo = 0, below_hi = 0;
    std::vector<double> in_lo, in_hi;
    for (const double v : values) {
        below_hi += v < hi_min ? 1 : 0;
        if (v >= hi_min && v <= hi_max) in_hi.push_back(v);
        if (!two) continue;
        below_lo += v < lo_min ? 1 : 0;
        if (v >= lo_min && v <= lo_max) in_lo.push_back(v);
    }
    const double hi = select_in(in_hi, below_hi, values, k_hi);
    if (!two) return {hi, hi};
    return {select_in(in_lo, below_lo, values, k_lo), hi};
}

double select_kth(std::vector<double>& values, std::size_t k) {
    if (k >= values.size()) throw std::invalid_argument("select_kth: rank beyond the values");
    return select_two(values, k, k).first;
}

namespace {

/// Rank floor(q * (n - 1)) of n > 0 values, q clamped to 0..1.
std::size_t quantile_rank(std::size_t n, double q) {
    return static_cast<std::size_t>(std::clamp(q, 0.0, 1.0) * static_cast<double>(n - 1));
}

}  // namespace

double median(std::vector<double> values) {
    const std::size_t n = values.size();
    if (n == 0) return 0.0;
    const auto [lo, hi] = select_two(values, (n - 1) / 2, n / 2);
    return 0.5 * (lo + hi);
}

double quantile(std::vector<double>& values, double q) {
    if (values.empty()) return 0.0;
    return select_kth(values, quantile_rank(values.size(), q));
}

std::pair<double, double> quantiles(std::vector<double>& values, double q_lo, double q_hi) {
    if (values.empty()) return {0.0, 0.0};
    return select_two(values, quantile_rank(values.size(), q_lo),
                      quantile_rank(values.size(), q_hi));
}

}  // namespace cloud_analysis
