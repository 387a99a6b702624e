#include <algorithm>
#include <cstddef>
#include <random>
#include <vector>

#include <catch2/catch.hpp>

#include "cloud_analysis/support/select.hpp"

using cloud_analysis::quantile;
using cloud_analysis::select_kth;

namespace {

/// The k-th smallest by a full sort.
double sorted_kth(std::vector<double> values, std::size_t k) {
    std::sort(values.begin(), values.end());
    return values[k];
}

}  // namespace

TEST_CASE("select_kth and select_two give the sorted array's values on large arrays of any order",
          "[select]") {
    std::mt19937 rng(5);
    std::normal_distribution<double> normal(0.0, 3.0);
    std::uniform_int_distribution<int> few(0, 7);
    const std::size_t n = 50000;  // above the size from which the array is narrowed
    std::vector<std::vector<double>> arrays(6, std::vector<double>(n));
    for (std::size_t i = 0; i < n; ++i) {
        arrays[0][i] = normal(rng);                    // random
        arrays[1][i] = static_cast<double>(i);         // sorted
        arrays[2][i] = -static_cast<double>(i);        // reversed
        arrays[3][i] = static_cast<double>(few(rng));  // many equal values
        arrays[4][i] = static_cast<double>(i % 1000);  // periodic, like pixel rows
        // The strided sample sees only zeros: its bracket misses every inner rank.
        arrays[5][i] = i % (n / 512) == (n / 512) / 2 ? 0.0 : static_cast<double>(i);
    }
    for (std::size_t a = 0; a < arrays.size(); ++a) {
        for (const std::size_t k :
             {std::size_t{0}, std::size_t{1}, n / 50, n / 2, n - n / 50, n - 2, n - 1}) {
            INFO("array " << a << ", k " << k);
            std::vector<double> copy = arrays[a];
            CHECK(select_kth(copy, k) == sorted_kth(arrays[a], k));
            const std::size_t k_hi = std::min(n - 1, k + n / 3);
            copy = arrays[a];
            const auto [lo, hi] = cloud_analysis::select_two(copy, k, k_hi);
            CHECK(lo == sorted_kth(arrays[a], k));
            CHECK(hi == sorted_kth(arrays[a], k_hi));
        }
    }
}

TEST_CASE("quantile takes rank floor(q * (n - 1)), clamps q and is 0 for no values", "[select]") {
    std::vector<double> v = {5.0, 1.0, 4.0, 2.0, 3.0};
    CHECK(quantile(v, 0.0) == 1.0);
    CHECK(quantile(v, 0.5) == 3.0);
    CHECK(quantile(v, 0.74) == 3.0);  // 0.74 * 4 = 2.96 -> rank 2
    CHECK(quantile(v, 0.75) == 4.0);  // 3.00 -> rank 3
    CHECK(quantile(v, 1.0) == 5.0);
    CHECK(quantile(v, 7.0) == 5.0);
    CHECK(quantile(v, -1.0) == 1.0);
    std::vector<double> none;
    CHECK(quantile(none, 0.5) == 0.0);
    CHECK_THROWS_AS(select_kth(v, 5), std::invalid_argument);
    CHECK_THROWS_AS(cloud_analysis::select_two(v, 3, 2), std::invalid_argument);
    const auto [lo, hi] = cloud_analysis::select_two(v, 1, 3);  // a small array
    CHECK(lo == 2.0);
    CHECK(hi == 4.0);
}

TEST_CASE(
    "median is the middle value, the mean of the two middle ones for an even count, and 0 "
    "for none",
    "[select]") {
    CHECK(cloud_analysis::median({5.0, 1.0, 4.0}) == 4.0);
    CHECK(cloud_analysis::median({5.0, 1.0, 4.0, 2.0}) == 3.0);
    CHECK(cloud_analysis::median({7.0}) == 7.0);
    CHECK(cloud_analysis::median({}) == 0.0);
    std::vector<double> many(10001);
    for (std::size_t i = 0; i < many.size(); ++i) many[i] = double((i * 7919) % many.size());
    CHECK(cloud_analysis::median(many) == 5000.0);
}
