#include "cloud_analysis/entities/row_split.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

#include "cloud_analysis/support/select.hpp"

namespace cloud_analysis::instances {
namespace {

constexpr double kGapFraction = 0.25;
constexpr double kHalfPi = 1.57079632679489661923;

/// Splits the points of a merged blob along the unit direction (dir_x, dir_z) into pieces of
/// about `prior_m`, cutting at the emptiest place near each even cut (touching parked cars).
/// With `from_near_end`, the cuts are walked from the end nearer the camera instead, each at
/// the emptiest place about `prior_m` beyond the previous one: the far end of a long row is
/// seen sparsely, so its extent (and an even division of it) is unreliable.
Split split_along(const std::vector<Eigen::Vector3f>& pts, const Indices& idx, double dir_x,
                  double dir_z, double extent_m, double prior_m, bool from_near_end = false) {
    const int pieces = std::max(2, static_cast<int>(std::lround(extent_m / prior_m)));
    std::vector<double> along(idx.size());
    double lo = 1e300, hi = -1e300;
    for (std::size_t k = 0; k < idx.size(); ++k) {
        along[k] = double{pts[idx[k]].x()} * dir_x + double{pts[idx[k]].z()} * dir_z;
        lo = std::min(lo, along[k]);
        hi = std::max(hi, along[k]);
    }
    // Density histogram along the direction, 0.1 m bins.
    const double bin = 0.1;
    const int bins = std::max(1, static_cast<int>(std::ceil((hi - lo) / bin)) + 1);
    std::vector<int> hist(static_cast<std::size_t>(bins), 0);
    for (double a : along) ++hist[static_cast<std::size_t>((a - lo) / bin)];
    std::vector<int> occupied;
    for (int h : hist) {
        if (h > 0) occupied.push_back(h);
    }
    std::nth_element(occupied.begin(), occupied.begin() + occupied.size() / 2, occupied.end());
    const double gap_count = kGapFraction * occupied[occupied.size() / 2];
    Split split;
    split.at_gaps = true;
    std::vector<double> cuts;
    const int reach = static_cast<int>(0.25 * prior_m / bin);
    const auto emptiest = [&](int centre) {
        int best = std::clamp(centre, 0, bins - 1);
        for (int b = std::max(0, centre - reach); b <= std::min(bins - 1, centre + reach); ++b) {
            if (hist[static_cast<std::size_t>(b)] < hist[static_cast<std::size_t>(best)]) best = b;
        }
        return best;
    };
    const int step = static_cast<int>(std::lround(prior_m / bin));
    const auto add_cut = [&](int best) {
        cuts.push_back(lo + (best + 0.5) * bin);
        if (hist[static_cast<std::size_t>(best)] > gap_count) split.at_gaps = false;
    };
    if (from_near_end && std::abs(hi) < std::abs(lo)) {
        for (int b = emptiest(bins - 1 - step); b >= step / 4; b = emptiest(b - step)) add_cut(b);
    } else if (from_near_end) {
        for (int b = emptiest(step); b < bins - step / 4; b = emptiest(b + step)) add_cut(b);
    }
    const double piece = (hi - lo) / pieces;
    for (int k = 1; k < pieces && !from_near_end; ++k) {
        add_cut(emptiest(static_cast<int>(k * piece / bin)));
    }
    std::sort(cuts.begin(), cuts.end());
    split.parts.resize(cuts.size() + 1);
    for (std::size_t k = 0; k < idx.size(); ++k) {
        const auto part = static_cast<std::size_t>(
            std::upper_bound(cuts.begin(), cuts.end(), along[k]) - cuts.begin());
        split.parts[part].push_back(idx[k]);
    }
    return split;
}

/// Whether a long blob is a row of things side by side seen front-on (or from behind) rather
/// than one thing seen side-on: its length along the box heading spans at least two prior
/// widths, and across the heading, from the camera's side, its top stays below
/// low_fraction * its highest top for at least low_extent_m (the bonnets in front of the
/// windscreens). A thing seen side-on shows its roof line over its whole visible width.
bool front_on_row(const std::vector<Eigen::Vector3f>& pts, const Indices& idx,
                  const OrientedBox& box, const ClassSettings& s, const GroundPlane& ground,
                  const ExtractOptions& options) {
    if (idx.size() < 20) return false;
    const double c = std::cos(box.theta), sn = std::sin(box.theta);
    std::vector<double> along, across;
    along.reserve(idx.size());
    across.reserve(idx.size());
    double min_along = std::numeric_limits<double>::infinity(), max_along = -min_along;
    for (std::size_t i : idx) {
        along.push_back(double{pts[i].x()} * c - double{pts[i].z()} * sn);
        across.push_back(double{pts[i].x()} * sn + double{pts[i].z()} * c);
        min_along = std::min(min_along, along.back());
        max_along = std::max(max_along, along.back());
    }
    // The whole extent bounds the 2-98 % one: most blobs (single things) stop here.
    if (max_along - min_along < 2.0 * s.prior_W_m) return false;
    const auto [along_lo, along_hi] = quantiles(along, 0.02, 0.98);
    const double length = along_hi - along_lo;
    if (length < 2.0 * s.prior_W_m) return false;
    std::vector<double> sorted = across;
    const auto [lo, hi] = quantiles(sorted, 0.02, 0.98);
    // Top (95 % height) per 0.1 m bin across, walked from the end nearer the camera.
    constexpr double kBin = 0.1;
    const int bins = static_cast<int>((hi - lo) / kBin) + 1;
    if (bins < 3) return false;
    std::vector<std::vector<double>> heights(static_cast<std::size_t>(bins));
    for (std::size_t k = 0; k < idx.size(); ++k) {
        const int b = static_cast<int>((across[k] - lo) / kBin);
        if (b < 0 || b >= bins) continue;
        heights[static_cast<std::size_t>(b)].push_back(ground.height(pts[idx[k]].cast<double>()));
    }
    constexpr std::size_t kMinBinPoints = 5;
    std::vector<double> top(static_cast<std::size_t>(bins), -1.0);
    double highest = 0.0;
    for (int b = 0; b < bins; ++b) {
        auto& h = heights[static_cast<std::size_t>(b)];
        if (h.size() < kMinBinPoints) continue;
        top[static_cast<std::size_t>(b)] = quantile(h, 0.95);
        highest = std::max(highest, top[static_cast<std::size_t>(b)]);
    }
    if (highest <= 0.0) return false;
    const bool near_is_lo = std::abs(lo) <= std::abs(hi);
    double low_extent = 0.0;
    for (int k = 0; k < bins; ++k) {
        const double t = top[static_cast<std::size_t>(near_is_lo ? k : bins - 1 - k)];
        if (t < 0.0) continue;
        if (t >= options.row_low_fraction * highest) break;
        low_extent = (k + 1) * kBin;
    }
    return low_extent >= options.row_low_extent_m;
}

}  // namespace

/// Vertical extent of points (2 % to 98 % height quantiles above the ground, or along -y
/// without a ground plane), metres.
double height_spread(const std::vector<Eigen::Vector3f>& pts, const Indices& idx,
                     const std::optional<GroundPlane>& ground) {
    std::vector<double> h;
    h.reserve(idx.size());
    for (std::size_t i : idx) {
        h.push_back(ground ? ground->height(pts[i].cast<double>()) : -double{pts[i].y()});
    }
    const auto [lo, hi] = quantiles(h, 0.02, 0.98);
    return hi - lo;
}

/// Pieces of a thing whose box is much longer or wider than its prior (a parked row, or
/// cars side by side merged by the semantic image); {idx} when it fits the prior.
Split split_oversized(const std::vector<Eigen::Vector3f>& pts, const Indices& idx,
                      const OrientedBox& box, const ClassSettings& s,
                      const std::optional<GroundPlane>& ground, const ExtractOptions& options) {
    if (!s.has_prior()) return {{idx}, false, std::nullopt};
    const double c = std::cos(box.theta), sn = std::sin(box.theta);
    if (ground && options.row_low_fraction > 0.0 &&
        front_on_row(pts, idx, box, s, *ground, options)) {
        // Side by side: cut along the box's length at the row's pitch; each piece heads across.
        Split split = split_along(pts, idx, c, -sn, box.L_m, s.prior_W_m + options.row_gap_m, true);
        split.yaw_rad = normalize_angle(box.theta + kHalfPi);
        split.at_gaps = true;  // a row of distinct things, whatever the density at the cuts
        return split;
    }
    if (box.L_m > s.split_factor * s.prior_L_m) {
        // Parked end to end: walk the gaps from the near end when there are gaps (the far end
        // is seen sparsely, so its extent is unreliable); touching things are cut evenly.
        Split walk = split_along(pts, idx, c, -sn, box.L_m, s.prior_L_m + options.row_gap_m, true);
        if (walk.at_gaps && walk.parts.size() > 1) return walk;
        return split_along(pts, idx, c, -sn, box.L_m, s.prior_L_m);
    }
    // Across the heading only for a clear double width: smear and oblique views widen single cars.
    if (box.W_m > std::max(s.split_factor, 1.9) * s.prior_W_m) {
        return split_along(pts, idx, sn, c, box.W_m, s.prior_W_m);
    }
    return {{idx}, false, std::nullopt};
}

}  // namespace cloud_analysis::instances
