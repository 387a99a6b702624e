#include "cloud_analysis/select.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <stdexcept>

namespace cloud_analysis {

double select_kth(std::vector<double>& values, std::size_t k) {
    const std::size_t n = values.size();
    if (k >= n) throw std::invalid_argument("select_kth: rank beyond the values");
    const auto at = [&values](std::size_t i) {
        return values.begin() + static_cast<std::ptrdiff_t>(i);
    };
    // Below this, std::nth_element on the whole array is as fast as narrowing it.
    constexpr std::size_t kNarrowFrom = 8192;
    constexpr std::size_t kSample = 1024;
    constexpr std::ptrdiff_t kMargin = 64;  // sample ranks either side: ~4 standard deviations
    if (n < kNarrowFrom) {
        std::nth_element(values.begin(), at(k), values.end());
        return values[k];
    }
    std::array<double, kSample> sample{};
    const std::size_t stride = n / kSample;
    for (std::size_t i = 0; i < kSample; ++i) sample[i] = values[i * stride + stride / 2];
    std::sort(sample.begin(), sample.end());
    const auto r = static_cast<std::ptrdiff_t>(static_cast<double>(k) * kSample / n);
    const double lo = r - kMargin < 0 ? -std::numeric_limits<double>::infinity()
                                      : sample[static_cast<std::size_t>(r - kMargin)];
    const double hi = r + kMargin >= static_cast<std::ptrdiff_t>(kSample)
                          ? std::numeric_limits<double>::infinity()
                          : sample[static_cast<std::size_t>(r + kMargin)];
    std::size_t below = 0;
    std::vector<double> bracket;
    bracket.reserve(n / 4);
    for (const double v : values) {
        if (v < lo) {
            ++below;
        } else if (v <= hi) {
            bracket.push_back(v);
        }
    }
    if (k >= below && k - below < bracket.size()) {
        const auto j = static_cast<std::ptrdiff_t>(k - below);
        std::nth_element(bracket.begin(), bracket.begin() + j, bracket.end());
        return bracket[static_cast<std::size_t>(j)];
    }
    std::nth_element(values.begin(), at(k), values.end());  // the bracket missed rank k
    return values[k];
}

double quantile(std::vector<double>& values, double q) {
    if (values.empty()) return 0.0;
    const auto k = static_cast<std::size_t>(
        std::clamp(q, 0.0, 1.0) * static_cast<double>(values.size() - 1) + 0.5);
    return select_kth(values, k);
}

}  // namespace cloud_analysis
