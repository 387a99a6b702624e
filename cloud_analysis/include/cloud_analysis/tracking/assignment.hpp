#pragma once

/// Minimum-cost assignment of rows to columns (Kuhn 1955, Munkres 1957: the Hungarian
/// method), with a gate: pairs that cost more than it are never matched.

#include <vector>

namespace cloud_analysis::tracking {

/// A cost matrix, rows x cols, row-major.
struct CostMatrix {
    int rows = 0;
    int cols = 0;
    std::vector<double> cost;  ///< rows * cols finite values
    double at(int r, int c) const { return cost[static_cast<std::size_t>(r) * cols + c]; }
};

/// One matched pair.
struct Match {
    int row = 0;
    int col = 0;
};

/// The pairs that minimise the total cost among those costing at most `gate` each, in row
/// order. Gated pairs are assigned as if they cost `gate` plus a margin larger than any sum of
/// real costs, so no real pair is given up to keep one over the gate; then those are dropped.
/// O(n^2 m) for n = min(rows, cols), m = max(rows, cols). Throws std::invalid_argument when
/// the matrix' size does not match rows * cols or a cost is not finite.
std::vector<Match> assign(const CostMatrix& matrix, double gate);

}  // namespace cloud_analysis::tracking
