#include "cloud_analysis/evaluation/hota.hpp"

#include <algorithm>
#include <cmath>
#include <map>
#include <stdexcept>

#include "cloud_analysis/tracking/assignment.hpp"

namespace cloud_analysis {
namespace {

constexpr int kAlphas = 19;  // 0.05, 0.10, ..., 0.95
constexpr double kEps = 1e-9;

double alpha_of(int a) { return 0.05 * (a + 1); }

using Pair = std::pair<std::int64_t, std::int64_t>;

}  // namespace

HotaScore hota(const std::vector<HotaFrame>& frames) {
    // Alignment of every truth/track pair over the drive: the sum over frames of the pair's
    // similarity divided by its row's and column's sums less itself (TrackEval's
    // potential matches), over truth frames + track frames - that sum.
    std::map<Pair, double> potential;
    std::map<std::int64_t, double> truth_count, track_count;
    for (const HotaFrame& f : frames) {
        const std::size_t n = f.truth.size(), m = f.tracks.size();
        if (f.similarity.size() != n * m)
            throw std::invalid_argument("hota: a frame's similarity matrix has the wrong size");
        std::vector<double> row(n, 0.0), col(m, 0.0);
        for (std::size_t t = 0; t < n; ++t) {
            for (std::size_t k = 0; k < m; ++k) {
                row[t] += f.similarity[t * m + k];
                col[k] += f.similarity[t * m + k];
            }
        }
        for (std::size_t t = 0; t < n; ++t) {
            for (std::size_t k = 0; k < m; ++k) {
                const double s = f.similarity[t * m + k];
                const double denominator = row[t] + col[k] - s;
                if (s > 0.0 && denominator > kEps)
                    potential[{f.truth[t], f.tracks[k]}] += s / denominator;
            }
        }
        for (auto id : f.truth) truth_count[id] += 1.0;
        for (auto id : f.tracks) track_count[id] += 1.0;
    }
    std::map<Pair, double> alignment;
    for (const auto& [pair, p] : potential)
        alignment[pair] = p / (truth_count[pair.first] + track_count[pair.second] - p);

    std::vector<double> tp(kAlphas, 0.0), fn(kAlphas, 0.0), fp(kAlphas, 0.0), loc(kAlphas, 0.0);
    std::vector<std::map<Pair, double>> matches(kAlphas);
    for (const HotaFrame& f : frames) {
        const std::size_t n = f.truth.size(), m = f.tracks.size();
        for (int a = 0; a < kAlphas; ++a) {
            fn[a] += static_cast<double>(n);
            fp[a] += static_cast<double>(m);
        }
        if (n == 0 || m == 0) continue;
        // Maximum total score: every pair admissible, cost 1 - score.
        tracking::CostMatrix costs{static_cast<int>(n), static_cast<int>(m), {}};
        for (std::size_t t = 0; t < n; ++t) {
            for (std::size_t k = 0; k < m; ++k) {
                const auto it = alignment.find({f.truth[t], f.tracks[k]});
                const double align = it == alignment.end() ? 0.0 : it->second;
                costs.cost.push_back(1.0 - align * f.similarity[t * m + k]);
            }
        }
        for (const auto& match : tracking::assign(costs, 2.0)) {
            const double s = f.similarity[match.row * m + match.col];
            for (int a = 0; a < kAlphas; ++a) {
                if (s < alpha_of(a) - kEps) continue;
                tp[a] += 1.0;
                fn[a] -= 1.0;
                fp[a] -= 1.0;
                loc[a] += s;
                matches[a][{f.truth[match.row], f.tracks[match.col]}] += 1.0;
            }
        }
    }
    HotaScore score;
    if (truth_count.empty() && track_count.empty()) return {1.0, 1.0, 1.0, 1.0};
    for (int a = 0; a < kAlphas; ++a) {
        double assa = 0.0;
        for (const auto& [pair, c] : matches[a]) {
            const double ass = c / (truth_count[pair.first] + track_count[pair.second] - c);
            assa += c * ass;
        }
        assa /= std::max(1.0, tp[a]);
        const double deta = tp[a] / std::max(1.0, tp[a] + fn[a] + fp[a]);
        score.hota += std::sqrt(deta * assa) / kAlphas;
        score.deta += deta / kAlphas;
        score.assa += assa / kAlphas;
        score.loca += (tp[a] > 0.0 ? loc[a] / tp[a] : 1.0) / kAlphas;
    }
    return score;
}

}  // namespace cloud_analysis
