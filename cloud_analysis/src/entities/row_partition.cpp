// A row of things parked end to end cut as one optimisation: the partition of its points along
// the row that best explains them as things of the class's lengths, parted where the evidence
// (clear gaps, valleys between roofs) says, found by dynamic programming over the cut positions.

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>

#include "cloud_analysis/support/select.hpp"
#include "row_split_internal.hpp"

namespace cloud_analysis::instances {
namespace {

/// Bins of the row's profiles along its length, metres.
constexpr double kBinM = 0.1;
/// The matcher's disparity noise, px: one surface at range r spreads over about this times
/// r^2 / fb along the viewing ray, which blurs each thing's length and the gaps between things.
constexpr double kDisparityNoisePx = 0.5;
/// The cost of a cut where nothing says two things meet (negative log-likelihood units): a cut
/// in a clear gap or a full valley costs nothing, one elsewhere this much, so a blob is parted
/// without evidence only when its length is that much less likely as one thing than as two.
constexpr double kBlindCutCost = 4.0;
/// Lengths of parked things of the size-family class (cars and vans, metres; Euro NCAP's
/// small to large family cars span 3.6-4.9 m, panel vans 4.9-5.5 m): mean, deviation, weight.
struct LengthMode {
    double mean_m, sd_m, weight;
};
constexpr std::array<LengthMode, 2> kFamilyLengths = {{{4.4, 0.4, 0.85}, {5.2, 0.35, 0.15}}};
/// A full valley between two roofs says this much of what a clear gap says of two things
/// meeting there: the gap is seen, the roofs' shapes are smeared along the viewing ray.
constexpr double kValleyWeight = 0.5;
/// Other classes: their prior length, this share of it as deviation.
constexpr double kPriorLengthShare = 0.15;
/// A piece's length is its points' extent between these quantiles (stray points at its ends).
constexpr double kExtentQuantile = 0.02;

/// The evidence of one row: per bin of its length, points, closed top, ranges.
struct RowEvidence {
    int bins = 0;
    double lo = 0.0;
    std::vector<double> count_prefix;       ///< points in bins [0, b)
    std::vector<double> range_prefix;       ///< their summed along-ray spread, metres
    std::vector<double> cut_evidence;       ///< per boundary b (before bin b), 0..1
    bool open_lo = false, open_hi = false;  ///< the piece at that end may be longer than shown
};

/// Per bin, the row's top (90 % height above the ground, -1 with fewer than 3 points), closed
/// over `closing` bins either side as top_profile does.
std::vector<double> closed_tops(const std::vector<std::vector<double>>& heights, int closing) {
    const int bins = static_cast<int>(heights.size());
    std::vector<double> top(heights.size(), -1.0);
    for (std::size_t b = 0; b < heights.size(); ++b) {
        std::vector<double> h = heights[b];
        if (h.size() >= 3) top[b] = quantile(h, 0.9);
    }
    std::vector<double> closed = top;
    for (int b = 0; b < bins; ++b) {
        if (top[static_cast<std::size_t>(b)] < 0.0) continue;
        for (int k = std::max(0, b - closing); k <= std::min(bins - 1, b + closing); ++k) {
            closed[static_cast<std::size_t>(b)] =
                std::max(closed[static_cast<std::size_t>(b)], top[static_cast<std::size_t>(k)]);
        }
    }
    return closed;
}

/// Per bin, how strongly it says two things meet there (0..1): 1 in a clear gap (a bin with
/// at most kGapFraction of the median occupied bin's points); elsewhere the depth of its top
/// below the lower of the highest dense tops within `reach` bins on either side, over
/// depth_m, when both reach min_peak_m (a valley between two roofs; sparse bins, smear in a
/// gap, are no roof), times the valley's fewest points over the bin's (plus one each): the two
/// things meet at the emptiest bin of the valley, where the gap between them is; a profile's
/// shape is smeared along the viewing ray, the gap's emptiness less so.
std::vector<double> bin_evidence(const std::vector<int>& count, const std::vector<double>& top,
                                 int reach, double depth_m, double min_peak_m) {
    const int bins = static_cast<int>(count.size());
    std::vector<int> occupied;
    for (int n : count) {
        if (n > 0) occupied.push_back(n);
    }
    std::nth_element(occupied.begin(), occupied.begin() + occupied.size() / 2, occupied.end());
    const double gap_count = kGapFraction * occupied[occupied.size() / 2];
    const auto is_gap = [&](int k) { return count[static_cast<std::size_t>(k)] <= gap_count; };
    const auto dense_top = [&](int k) {
        return is_gap(k) ? -1.0 : top[static_cast<std::size_t>(k)];
    };
    std::vector<double> evidence(count.size(), 0.0);
    for (int b = 0; b < bins; ++b) {
        const auto k = static_cast<std::size_t>(b);
        if (is_gap(b)) {
            evidence[k] = 1.0;
            continue;
        }
        double left = -1.0, right = -1.0;
        for (int j = std::max(0, b - reach); j < b; ++j) left = std::max(left, dense_top(j));
        for (int j = b + 1; j <= std::min(bins - 1, b + reach); ++j) {
            right = std::max(right, dense_top(j));
        }
        const double peak = std::min(left, right);
        if (top[k] < 0.0 || peak < min_peak_m) continue;
        evidence[k] = kValleyWeight * std::clamp((peak - top[k]) / depth_m, 0.0, 1.0);
    }
    for (int b = 0; b < bins;) {
        const auto in_valley = [&](int k) {
            const auto u = static_cast<std::size_t>(k);
            return evidence[u] > 0.0 && !is_gap(k);
        };
        if (!in_valley(b)) {
            ++b;
            continue;
        }
        int e = b, fewest = count[static_cast<std::size_t>(b)];
        while (e + 1 < bins && in_valley(e + 1))
            fewest = std::min(fewest, count[static_cast<std::size_t>(++e)]);
        for (int k = b; k <= e; ++k) {
            evidence[static_cast<std::size_t>(k)] *=
                (fewest + 1.0) / (count[static_cast<std::size_t>(k)] + 1.0);
        }
        b = e + 1;
    }
    return evidence;
}

RowEvidence row_evidence(const std::vector<Eigen::Vector3f>& pts, const Indices& idx,
                         const Projection& p, double dir_x, double dir_z, const ClassSettings& s,
                         const GroundPlane& ground, const ExtractOptions& options,
                         const std::optional<Eigen::Vector2d>& truncation_xz, double fb_px_m) {
    RowEvidence ev;
    ev.lo = p.lo;
    ev.bins = std::max(1, static_cast<int>(std::ceil((p.hi - p.lo) / kBinM)) + 1);
    if (truncation_xz) {
        const double at = truncation_xz->x() * dir_x + truncation_xz->y() * dir_z;
        (std::abs(at - p.lo) <= std::abs(at - p.hi) ? ev.open_lo : ev.open_hi) = true;
    }
    const auto n = static_cast<std::size_t>(ev.bins);
    std::vector<int> count(n, 0);
    std::vector<double> spread(n, 0.0);
    std::vector<std::vector<double>> heights(n);
    for (std::size_t k = 0; k < idx.size(); ++k) {
        const auto b = static_cast<std::size_t>((p.along[k] - p.lo) / kBinM);
        const Eigen::Vector3d q = pts[idx[k]].cast<double>();
        ++count[b];
        heights[b].push_back(ground.height(q));
        const double r = std::hypot(q.x(), q.z());
        if (fb_px_m > 0.0 && r > 0.0) {
            const double along_ray = std::abs(q.x() * dir_x + q.z() * dir_z) / r;
            spread[b] += kDisparityNoisePx * r * r / fb_px_m * along_ray;
        }
    }
    const int closing = static_cast<int>(std::lround(options.row_valley_closing_m / kBinM));
    const int reach = std::max(1, static_cast<int>(std::lround(0.5 * s.prior_L_m / kBinM)));
    const std::vector<double> evidence =
        bin_evidence(count, closed_tops(heights, closing), reach, options.row_valley_depth_m,
                     options.row_valley_min_peak_fraction * s.prior_H_m);
    ev.count_prefix.assign(n + 1, 0.0);
    ev.range_prefix.assign(n + 1, 0.0);
    ev.cut_evidence.assign(n + 1, 0.0);
    for (std::size_t b = 0; b < n; ++b) {
        ev.count_prefix[b + 1] = ev.count_prefix[b] + count[b];
        ev.range_prefix[b + 1] = ev.range_prefix[b] + spread[b];
        ev.cut_evidence[b] = std::max(evidence[b], b > 0 ? evidence[b - 1] : 0.0);
    }
    return ev;
}

/// The along-coordinate bin (fractional) holding the point of rank `rank` among bins [i, j).
double bin_at_rank(const RowEvidence& ev, int i, int j, double rank) {
    const auto first = ev.count_prefix.begin() + i;
    const auto last = ev.count_prefix.begin() + j + 1;
    const double target = ev.count_prefix[static_cast<std::size_t>(i)] + rank;
    const auto it = std::upper_bound(first, last, target);
    return static_cast<double>(std::max<std::ptrdiff_t>(it - ev.count_prefix.begin() - 1, i));
}

constexpr double kSqrt2 = 1.4142135623730951;

double normal_pdf(double x, double sd) {
    constexpr double kInvSqrt2Pi = 0.3989422804014327;
    return kInvSqrt2Pi / sd * std::exp(-0.5 * (x / sd) * (x / sd));
}

/// The negative log-likelihood of bins [i, j) being one thing: its length (2-98 % extent) under
/// the class's length distribution blurred by the range spread there; a piece at an open end
/// of the row may be longer than it shows (hidden behind the thing before it, past what the
/// matcher sees, or beyond the image's edge), its visible length anywhere up to its own.
double piece_cost(const RowEvidence& ev, int i, int j, const ClassSettings& s,
                  const std::vector<LengthMode>& modes, std::size_t min_points) {
    const double n =
        ev.count_prefix[static_cast<std::size_t>(j)] - ev.count_prefix[static_cast<std::size_t>(i)];
    if (n < static_cast<double>(min_points)) return std::numeric_limits<double>::infinity();
    const double first = bin_at_rank(ev, i, j, kExtentQuantile * n);
    const double last = bin_at_rank(ev, i, j, (1.0 - kExtentQuantile) * n);
    const double length = (last - first + 1.0) * kBinM;
    const double blur = (ev.range_prefix[static_cast<std::size_t>(j)] -
                         ev.range_prefix[static_cast<std::size_t>(i)]) /
                        n;
    const bool open = (ev.open_lo && i == 0) || (ev.open_hi && j == ev.bins);
    double likelihood = 0.0;
    for (const LengthMode& m : modes) {
        const double sd = std::hypot(m.sd_m, blur);
        // A thing cut by an end shows a length spread evenly over [0, its length]: the density
        // of seeing `length` is the chance it is at least that long over its mean length.
        likelihood +=
            m.weight * (open ? 0.5 * std::erfc((length - m.mean_m) / (sd * kSqrt2)) / m.mean_m
                             : normal_pdf(length - m.mean_m, sd));
    }
    (void)s;
    return -std::log(std::max(likelihood, 1e-300));
}

}  // namespace

Split partition_row(const std::vector<Eigen::Vector3f>& pts, const Indices& idx, double dir_x,
                    double dir_z, const ClassSettings& s, const GroundPlane& ground,
                    const ExtractOptions& options,
                    const std::optional<Eigen::Vector2d>& truncation_xz, double fb_px_m) {
    Split split{{idx}, false, std::nullopt};
    if (idx.size() < 20) return split;
    const Projection p = project(pts, idx, dir_x, dir_z);
    const RowEvidence ev =
        row_evidence(pts, idx, p, dir_x, dir_z, s, ground, options, truncation_xz, fb_px_m);
    std::vector<LengthMode> modes;
    if (!options.family_class.empty() && s.name == options.family_class) {
        modes.assign(kFamilyLengths.begin(), kFamilyLengths.end());
    } else {
        modes.push_back({s.prior_L_m, kPriorLengthShare * s.prior_L_m, 1.0});
    }
    const auto min_points = static_cast<std::size_t>(std::max(1, s.min_points / 2));
    // best[j]: the least cost of bins [0, j) as whole things; from[j]: where its last starts.
    const int bins = ev.bins;
    std::vector<double> best(static_cast<std::size_t>(bins) + 1,
                             std::numeric_limits<double>::infinity());
    std::vector<int> from(static_cast<std::size_t>(bins) + 1, 0);
    best[0] = 0.0;
    for (int j = 1; j <= bins; ++j) {
        for (int i = 0; i < j; ++i) {
            if (!std::isfinite(best[static_cast<std::size_t>(i)])) continue;
            const double cut =
                i == 0 ? 0.0 : kBlindCutCost * (1.0 - ev.cut_evidence[static_cast<std::size_t>(i)]);
            const double cost = best[static_cast<std::size_t>(i)] + cut +
                                piece_cost(ev, i, j, s, modes, min_points);
            if (cost < best[static_cast<std::size_t>(j)]) {
                best[static_cast<std::size_t>(j)] = cost;
                from[static_cast<std::size_t>(j)] = i;
            }
        }
    }
    if (!std::isfinite(best[static_cast<std::size_t>(bins)])) return split;
    std::vector<double> cuts;
    split.at_gaps = true;
    for (int j = bins; from[static_cast<std::size_t>(j)] > 0;
         j = from[static_cast<std::size_t>(j)]) {
        const int i = from[static_cast<std::size_t>(j)];
        cuts.push_back(ev.lo + i * kBinM);
        if (ev.cut_evidence[static_cast<std::size_t>(i)] < 1.0) split.at_gaps = false;
    }
    if (cuts.empty()) return split;
    std::sort(cuts.begin(), cuts.end());
    split.parts.assign(cuts.size() + 1, {});
    for (std::size_t k = 0; k < idx.size(); ++k) {
        const auto part = static_cast<std::size_t>(
            std::upper_bound(cuts.begin(), cuts.end(), p.along[k]) - cuts.begin());
        split.parts[part].push_back(idx[k]);
    }
    return split;
}

}  // namespace cloud_analysis::instances
