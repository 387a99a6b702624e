#include "cloud_analysis/entities/smear.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

#include "cloud_analysis/entities/suppression.hpp"
#include "stereoscene/support/angles.hpp"

using stereoscene::support::kPi;
using stereoscene::support::radians;

namespace cloud_analysis::instances {
namespace {

/// Azimuth bin of a point: lround(atan2(x, z) / 0.5 degrees), clamped to +-360, plus 360.
/// In front of the camera (z > 0, |x / z| < kMaxSlope) the bin comes from the slope x / z
/// compared with the tangents of the bin boundaries (a uniform grid of slopes finer than any
/// bin gives the candidate, one or two comparisons settle it) instead of a call to atan2: the
/// same bins, up to rounding within ~1e-15 of a boundary.
class AzimuthBins {
  public:
    static constexpr double kBinRad = radians(0.5);
    static constexpr long kBins = 360;  // |atan2| <= pi is at most 360 bins either side

    AzimuthBins() {
        // upper_[b + 180] = tan of the upper boundary of bin b, b in [-180, 180).
        for (long b = -180; b < 180; ++b) upper_.push_back(std::tan((b + 0.5) * kBinRad));
        const auto cells = static_cast<std::size_t>(2.0 * kMaxSlope / kStep) + 2;
        for (std::size_t c = 0; c < cells; ++c) {
            first_.push_back(settle(-180, -kMaxSlope + static_cast<double>(c) * kStep));
        }
    }
    long operator()(double x, double z) const {
        if (z > 0.0) {
            const double t = x / z;
            if (t > -kMaxSlope && t < kMaxSlope) {
                const auto c = static_cast<std::size_t>((t + kMaxSlope) * (1.0 / kStep));
                return settle(first_[c], t) + kBins;
            }
        }
        return std::clamp(std::lround(std::atan2(x, z) / kBinRad), -kBins, kBins) + kBins;
    }

  private:
    static constexpr double kMaxSlope = 4.0;  // |x / z| below this (76 degrees) is looked up
    static constexpr double kStep = 0.004;    // slope grid step; a bin spans >= 0.0087
    /// The bin (in [-180, 180]) of slope t: the first whose upper boundary lies above t,
    /// walked to from bin b.
    long settle(long b, double t) const {
        while (b < 180 && !(t < upper_[static_cast<std::size_t>(b + 180)])) ++b;
        while (b > -180 && t < upper_[static_cast<std::size_t>(b + 179)]) --b;
        return b;
    }
    std::vector<double> upper_;
    std::vector<long> first_;  ///< bin of the lower end of each grid cell
};

}  // namespace

/// Drops stereo smear behind a thing: per viewing direction (0.5 degree azimuth bins), points
/// farther (bird's-eye range) than the nearest one plus the prior's diagonal plus a margin;
/// and points implausibly high above or below the ground. `behind`, when given, receives the
/// points dropped for their range.
Indices drop_outliers(const std::vector<Eigen::Vector3f>& pts, const Indices& idx,
                      const ClassSettings& s, const std::optional<GroundPlane>& ground,
                      double margin_m, Indices* behind) {
    if (!s.has_prior() || idx.size() < 10) return idx;
    static const AzimuthBins azimuth_bin;
    std::vector<double> range(idx.size());
    std::vector<long> bin(idx.size());
    std::vector<double> nearest(2 * AzimuthBins::kBins + 1,
                                std::numeric_limits<double>::infinity());
    for (std::size_t k = 0; k < idx.size(); ++k) {
        const double x = pts[idx[k]].x(), z = pts[idx[k]].z();
        range[k] = std::sqrt(x * x + z * z);  // float inputs: no overflow for hypot to guard
        bin[k] = azimuth_bin(x, z);
        double& n = nearest[static_cast<std::size_t>(bin[k])];
        n = std::min(n, range[k]);
    }
    const double depth = std::hypot(s.prior_L_m, s.prior_W_m) + margin_m;
    Indices kept;
    kept.reserve(idx.size());
    Indices far;
    for (std::size_t k = 0; k < idx.size(); ++k) {
        if (range[k] > nearest[static_cast<std::size_t>(bin[k])] + depth) {
            far.push_back(idx[k]);
            continue;
        }
        if (ground) {
            const double h = ground->height(pts[idx[k]].cast<double>());
            if (h < -0.5 || h > 1.5 * s.prior_H_m + 0.5) continue;
        }
        kept.push_back(idx[k]);
    }
    if (kept.size() < static_cast<std::size_t>(s.min_points)) return idx;
    if (behind) *behind = std::move(far);
    return kept;
}

/// The members whose pixels are not on the far side of a depth step (PixelGrid::depth_edge),
/// when at least min_points of them remain (the others in `on_edge`); all of them otherwise (a
/// thing seen only as a strip over a nearer one has nothing better).
Indices off_depth_edges(const std::vector<std::uint32_t>& pixels, const PixelGrid& grid,
                        Indices members, const ClassSettings& s, Indices& on_edge) {
    if (grid.depth_edge == nullptr || pixels.empty()) return members;
    const std::vector<std::uint8_t>& edge = *grid.depth_edge;
    Indices kept, dropped;
    kept.reserve(members.size());
    for (std::size_t i : members) {
        (edge[pixels[i]] == 0 ? kept : dropped).push_back(i);
    }
    if (kept.size() < static_cast<std::size_t>(s.min_points)) return members;
    on_edge = std::move(dropped);
    return kept;
}

/// The points on a depth edge that a cluster's boxes were fitted without, each given back to
/// the candidate whose box footprint lies nearest it, within kEdgePointReach: they are seen
/// surface of that thing, at a mixed depth, and count as such (point count, seen area, image
/// extent) though they do not shape its box. Farther ones are dropped.
void give_back_edge_points(const std::vector<Eigen::Vector3f>& pts, const Indices& on_edge,
                           std::vector<Candidate>& candidates) {
    constexpr double kEdgePointReach = 1.0;  // metres: beside the box, at most
    if (on_edge.empty() || candidates.empty()) return;
    std::vector<Footprint> footprints;
    footprints.reserve(candidates.size());
    for (const Candidate& c : candidates) footprints.push_back(footprint_of(c.box));
    // Per candidate: its members before the edge points it takes (0: none taken).
    std::vector<std::size_t> had(candidates.size(), 0);
    std::vector<char> grown(candidates.size(), 0);
    for (std::size_t i : on_edge) {
        double best = kEdgePointReach;
        std::size_t to = candidates.size();
        for (std::size_t k = 0; k < candidates.size(); ++k) {
            const double d = footprints[k].distance_m(pts[i].x(), pts[i].z());
            if (d < best) {
                best = d;
                to = k;
            }
        }
        if (to == candidates.size()) continue;
        if (!grown[to]) had[to] = candidates[to].members.size();
        candidates[to].members.push_back(i);
        grown[to] = 1;
    }
    for (std::size_t k = 0; k < candidates.size(); ++k) {
        if (!grown[k]) continue;
        auto& m = candidates[k].members;
        const auto middle = m.begin() + static_cast<std::ptrdiff_t>(had[k]);
        if (std::is_sorted(m.begin(), middle) && std::is_sorted(middle, m.end())) {
            std::inplace_merge(m.begin(), middle, m.end());  // the same order, in linear time
        } else {
            std::sort(m.begin(), m.end());
        }
    }
}

}  // namespace cloud_analysis::instances
