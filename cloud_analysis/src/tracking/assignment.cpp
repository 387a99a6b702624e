#include "cloud_analysis/tracking/assignment.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>

namespace cloud_analysis::tracking {

namespace {

/// Hungarian method with potentials for n <= m (rows <= columns): returns col_of_row.
/// a is 1-based: a[i][j], i in 1..n, j in 1..m.
std::vector<int> hungarian(const std::vector<std::vector<double>>& a, int n, int m) {
    const double inf = std::numeric_limits<double>::infinity();
    std::vector<double> u(n + 1, 0.0), v(m + 1, 0.0), minv(m + 1);
    std::vector<int> p(m + 1, 0), way(m + 1, 0);
    std::vector<char> used(m + 1);
    for (int i = 1; i <= n; ++i) {
        p[0] = i;
        int j0 = 0;
        std::fill(minv.begin(), minv.end(), inf);
        std::fill(used.begin(), used.end(), 0);
        do {
            used[j0] = 1;
            const int i0 = p[j0];
            double delta = inf;
            int j1 = 0;
            for (int j = 1; j <= m; ++j) {
                if (used[j]) continue;
                const double cur = a[i0][j] - u[i0] - v[j];
                if (cur < minv[j]) {
                    minv[j] = cur;
                    way[j] = j0;
                }
                if (minv[j] < delta) {
                    delta = minv[j];
                    j1 = j;
                }
            }
            for (int j = 0; j <= m; ++j) {
                if (used[j]) {
                    u[p[j]] += delta;
                    v[j] -= delta;
                } else {
                    minv[j] -= delta;
                }
            }
            j0 = j1;
        } while (p[j0] != 0);
        do {
            const int j1 = way[j0];
            p[j0] = p[j1];
            j0 = j1;
        } while (j0 != 0);
    }
    std::vector<int> col_of_row(n + 1, 0);
    for (int j = 1; j <= m; ++j) {
        if (p[j] != 0) col_of_row[p[j]] = j;
    }
    return col_of_row;
}

}  // namespace

std::vector<Match> assign(const CostMatrix& matrix, double gate) {
    if (matrix.rows < 0 || matrix.cols < 0 ||
        matrix.cost.size() != static_cast<std::size_t>(matrix.rows) * matrix.cols) {
        throw std::invalid_argument("assign: the cost matrix' size is not rows * cols");
    }
    double total = 0.0;
    for (double c : matrix.cost) {
        if (!std::isfinite(c)) throw std::invalid_argument("assign: a cost is not finite");
        if (c <= gate) total += std::abs(c);
    }
    if (matrix.rows == 0 || matrix.cols == 0) return {};
    // A gated pair costs more than every admissible assignment could: the optimum first keeps
    // as many admissible pairs as possible, then minimises their cost.
    const double gated = std::abs(gate) + 2.0 * total + 1.0;
    const bool transpose = matrix.rows > matrix.cols;
    const int n = transpose ? matrix.cols : matrix.rows;
    const int m = transpose ? matrix.rows : matrix.cols;
    std::vector<std::vector<double>> a(n + 1, std::vector<double>(m + 1, 0.0));
    for (int i = 1; i <= n; ++i) {
        for (int j = 1; j <= m; ++j) {
            const double c = transpose ? matrix.at(j - 1, i - 1) : matrix.at(i - 1, j - 1);
            a[i][j] = c <= gate ? c : gated;
        }
    }
    const std::vector<int> col_of_row = hungarian(a, n, m);
    std::vector<Match> matches;
    for (int i = 1; i <= n; ++i) {
        const int j = col_of_row[i];
        if (j == 0) continue;
        const Match match = transpose ? Match{j - 1, i - 1} : Match{i - 1, j - 1};
        if (matrix.at(match.row, match.col) <= gate) matches.push_back(match);
    }
    std::sort(matches.begin(), matches.end(),
              [](const Match& l, const Match& r) { return l.row < r.row; });
    return matches;
}

}  // namespace cloud_analysis::tracking
