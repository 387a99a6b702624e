#pragma once

/// Order statistics of large arrays: the value std::nth_element would put at position k,
/// found in about one pass.

#include <cstddef>
#include <utility>
#include <vector>

namespace cloud_analysis {

/// The k-th smallest of `values` (0-based, k < size), exactly as std::nth_element finds it;
/// the values may be reordered. Large arrays are narrowed first: a strided sample's order
/// statistics bracket rank k, one pass counts the values below the bracket and keeps those in
/// it, and only those are selected from (the whole array when the bracket misses, which keeps
/// the answer exact whatever the order of the values).
double select_kth(std::vector<double>& values, std::size_t k);

/// The k_lo-th and k_hi-th smallest of `values` (k_lo <= k_hi < size), as select_kth gives
/// them, from one sample and one pass.
std::pair<double, double> select_two(std::vector<double>& values, std::size_t k_lo,
                                     std::size_t k_hi);

/// The median of `values`: the middle value, or the mean of the two middle values of an even
/// count; 0 for no values.
double median(std::vector<double> values);

/// The value at fraction q (clamped to 0..1) of the sorted values: rank floor(q * (n - 1));
/// the values may be reordered. 0 for no values.
double quantile(std::vector<double>& values, double q);

/// The values at fractions q_lo <= q_hi, as quantile() gives each, from one pass; {0, 0} for
/// no values.
std::pair<double, double> quantiles(std::vector<double>& values, double q_lo, double q_hi);

}  // namespace cloud_analysis
