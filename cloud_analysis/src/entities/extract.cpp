#include "cloud_analysis/entities/extract.hpp"

#include <algorithm>
#include <atomic>
#include <cmath>
#include <condition_variable>
#include <cstdint>
#include <deque>
#include <exception>
#include <functional>
#include <future>
#include <limits>
#include <memory>
#include <mutex>
#include <stdexcept>
#include <thread>
#include <tuple>
#include <utility>

#include "cloud_analysis/entities/boxes.hpp"
#include "cloud_analysis/entities/cluster.hpp"
#include "cloud_analysis/support/select.hpp"

namespace cloud_analysis {
namespace {

using Indices = std::vector<std::size_t>;
/// The ground plane, fitted on one thread while the classes are clustered on the others.
using PendingGround = std::shared_future<std::optional<GroundPlane>>;

/// The points of clusters of voxels, in point order (not the order the clustering visited
/// them in, so that strided samples of a cluster are spread evenly over its pixels).
std::vector<Indices> points_of(const std::vector<Indices>& voxel_clusters,
                               const VoxelGrid& voxels) {
    constexpr auto kNone = static_cast<std::size_t>(-1);
    std::vector<std::size_t> cluster_of(voxels.centroid_m.size(), kNone);
    for (std::size_t c = 0; c < voxel_clusters.size(); ++c) {
        for (std::size_t v : voxel_clusters[c]) cluster_of[v] = c;
    }
    std::vector<Indices> out(voxel_clusters.size());
    for (std::size_t i = 0; i < voxels.voxel_of.size(); ++i) {
        const std::size_t c = cluster_of[voxels.voxel_of[i]];
        if (c != kNone) out[c].push_back(i);
    }
    return out;
}

/// The points pts[idx[0]], pts[idx[1]], ...
std::vector<Eigen::Vector3f> gather(const std::vector<Eigen::Vector3f>& pts, const Indices& idx) {
    std::vector<Eigen::Vector3f> out;
    out.reserve(idx.size());
    for (std::size_t i : idx) out.push_back(pts[i]);
    return out;
}

/// Azimuth bin of a point: lround(atan2(x, z) / 0.5 degrees), clamped to +-360, plus 360.
/// In front of the camera (z > 0, |x / z| < kMaxSlope) the bin comes from the slope x / z
/// compared with the tangents of the bin boundaries (a uniform grid of slopes finer than any
/// bin gives the candidate, one or two comparisons settle it) instead of a call to atan2: the
/// same bins, up to rounding within ~1e-15 of a boundary.
class AzimuthBins {
  public:
    static constexpr double kBinRad = 0.5 * 3.14159265358979323846 / 180.0;
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

/// Drops stereo smear behind a thing: per viewing direction (0.5 degree azimuth bins), points
/// farther (bird's-eye range) than the nearest one plus the prior's diagonal plus a margin;
/// and points implausibly high above or below the ground.
Indices drop_outliers(const std::vector<Eigen::Vector3f>& pts, const Indices& idx,
                      const ClassSettings& s, const std::optional<GroundPlane>& ground,
                      double margin_m) {
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
    for (std::size_t k = 0; k < idx.size(); ++k) {
        if (range[k] > nearest[static_cast<std::size_t>(bin[k])] + depth) continue;
        if (ground) {
            const double h = ground->height(pts[idx[k]].cast<double>());
            if (h < -0.5 || h > 1.5 * s.prior_H_m + 0.5) continue;
        }
        kept.push_back(idx[k]);
    }
    return kept.size() >= static_cast<std::size_t>(s.min_points) ? kept : idx;
}

/// Pieces of a split blob; at_gaps when every cut fell in a clear gap (a bin with at most
/// kGapFraction of the median occupied bin's points): the pieces are then distinct objects.
struct Split {
    std::vector<Indices> parts;
    bool at_gaps = false;
    std::optional<double> yaw_rad;  ///< heading imposed on the pieces (cars side by side)
};
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

scene_schema::Entity make_entity(const ClassInfo& info, const OrientedBox& box,
                                 std::size_t point_count, double confidence,
                                 const std::string& method) {
    scene_schema::Entity e;
    e.class_name = info.name;
    e.class_id = info.id;
    e.x = box.centre_m.x();
    e.y = box.centre_m.y();
    e.z = box.centre_m.z();
    e.theta = box.theta;
    e.L = std::max(box.L_m, 1e-3);
    e.W = std::max(box.W_m, 1e-3);
    e.H = std::max(box.H_m, 1e-3);
    e.point_count = static_cast<std::int64_t>(point_count);
    e.confidence = std::clamp(confidence, 0.0, 1.0);
    e.method = method;
    return e;
}

/// A thing's bird's-eye footprint: centre, heading's cosine and sine, half length and width.
struct Footprint {
    double x, z, c, s, half_L, half_W;
};

std::vector<Footprint> footprints_of(const std::vector<scene_schema::Entity>& things) {
    std::vector<Footprint> out;
    out.reserve(things.size());
    for (const auto& t : things) {
        out.push_back({t.x, t.z, std::cos(t.theta), std::sin(t.theta), t.L / 2.0, t.W / 2.0});
    }
    return out;
}

/// Share of the bird's-eye footprint of `e` (sampled on a kSamples x kSamples grid of cell
/// centres) inside any of the `things` footprints.
double footprint_share_inside(const scene_schema::Entity& e, const std::vector<Footprint>& things) {
    constexpr int kSamples = 10;
    const double c = std::cos(e.theta), sn = std::sin(e.theta);
    int inside = 0;
    for (int i = 0; i < kSamples; ++i) {
        for (int j = 0; j < kSamples; ++j) {
            // Heading (cos t, -sin t) in x-z; across it (sin t, cos t).
            const double a = ((i + 0.5) / kSamples - 0.5) * e.L;
            const double b = ((j + 0.5) / kSamples - 0.5) * e.W;
            const double x = e.x + a * c + b * sn, z = e.z - a * sn + b * c;
            for (const auto& t : things) {
                const double dx = x - t.x, dz = z - t.z;
                if (std::abs(dx * t.c - dz * t.s) <= t.half_L &&
                    std::abs(dx * t.s + dz * t.c) <= t.half_W) {
                    ++inside;
                    break;
                }
            }
        }
    }
    return static_cast<double>(inside) / (kSamples * kSamples);
}

/// confidence = n / (n + 2 * min_points): 1/3 at the minimum, -> 1 with many points.
double confidence_of(std::size_t n, const ClassSettings& s) {
    const double dn = static_cast<double>(n);
    return dn / (dn + 2.0 * s.min_points);
}

/// Pixel grid of the source image, to reason about clusters in image space.
struct PixelGrid {
    int width_px = 0;
    int height_px = 0;
    bool valid() const { return width_px > 0 && height_px > 0; }
};

/// One thing instance before it becomes an entity.
struct Candidate {
    OrientedBox box;
    Indices members;
    double range_m = 0.0;   ///< mean bird's-eye range of the points
    std::size_t group = 0;  ///< pieces cut from one 3D cluster at clear gaps share a group
    bool fragment = false;  ///< short (a strip) or sparse (under min_points): edge smear?
};

/// Image-space suppression of "shadows" (candidates visited nearest first, tested against the
/// accepted ones of other groups nearer by more than min_gap_m):
/// - a candidate with most of its pixels inside the row extents of a nearer candidate (its
///   leftmost to rightmost pixel on each row) is dropped: pixels
///   interleaved with a nearer object's are wrong matches on it (dark, textureless car bodies,
///   holes in its disparity) reprojected too far. A real object behind another is occluded
///   there and shows only beside it, so a candidate beside a nearer one is kept;
/// - a fragment (short or sparse) is dropped when most of its pixels lie within radius_px of
///   those extents on any row within radius_px above or below: stereo smear along a nearer
///   object's edges (roof lines matched to the background) is a thin strip beside it.
/// Pieces of one group (a parked row cut at clear gaps) never suppress each other: each is a
/// distinct object and the row is connected in space, which a shadow is not.
std::vector<Candidate> suppress_shadows(std::vector<Candidate> candidates,
                                        const std::vector<std::uint32_t>& pixels,
                                        const PixelGrid& grid, double min_gap_m,
                                        double max_shared_fraction, int radius_px) {
    if (!grid.valid() || candidates.size() < 2) return candidates;
    std::stable_sort(candidates.begin(), candidates.end(),
                     [](const auto& a, const auto& b) { return a.range_m < b.range_m; });
    // Per image row, the column extent of every accepted candidate's pixels on that row.
    struct Extent {
        int lo_px;
        int hi_px;
        float range_m;
        std::size_t group;
    };
    std::vector<std::vector<Extent>> rows(static_cast<std::size_t>(grid.height_px));
    const auto width = static_cast<std::uint32_t>(grid.width_px);
    std::vector<Candidate> kept;
    for (auto& c : candidates) {
        const int reach = c.fragment ? radius_px : 0;
        std::size_t shared = 0;
        for (std::size_t i : c.members) {
            const int u = static_cast<int>(pixels[i] % width);
            const int v = static_cast<int>(pixels[i] / width);
            bool inside = false;
            for (int r = std::max(0, v - reach);
                 r <= std::min(grid.height_px - 1, v + reach) && !inside; ++r) {
                for (const Extent& e : rows[static_cast<std::size_t>(r)]) {
                    if (e.group != c.group && double{e.range_m} + min_gap_m < c.range_m &&
                        u >= e.lo_px - reach && u <= e.hi_px + reach) {
                        inside = true;
                        break;
                    }
                }
            }
            shared += inside ? 1 : 0;
        }
        if (static_cast<double>(shared) >
            max_shared_fraction * static_cast<double>(c.members.size())) {
            continue;
        }
        std::vector<int> lo(rows.size(), grid.width_px), hi(rows.size(), -1);
        for (std::size_t i : c.members) {
            const int u = static_cast<int>(pixels[i] % width);
            const std::size_t v = pixels[i] / width;
            lo[v] = std::min(lo[v], u);
            hi[v] = std::max(hi[v], u);
        }
        for (std::size_t v = 0; v < rows.size(); ++v) {
            if (hi[v] >= 0)
                rows[v].push_back({lo[v], hi[v], static_cast<float>(c.range_m), c.group});
        }
        kept.push_back(std::move(c));
    }
    return kept;
}

/// Drops thing candidates whose centre lies inside the footprint of a candidate with more
/// points: two objects cannot overlap that much, so the smaller is a fragment of the larger.
std::vector<Candidate> suppress_nested(std::vector<Candidate> candidates) {
    std::stable_sort(candidates.begin(), candidates.end(), [](const auto& a, const auto& b) {
        return a.members.size() > b.members.size();
    });
    std::vector<Candidate> kept;
    for (auto& c : candidates) {
        bool nested = false;
        for (const auto& k : kept) {
            const double dx = c.box.centre_m.x() - k.box.centre_m.x();
            const double dz = c.box.centre_m.z() - k.box.centre_m.z();
            const double along = dx * std::cos(k.box.theta) - dz * std::sin(k.box.theta);
            const double across = dx * std::sin(k.box.theta) + dz * std::cos(k.box.theta);
            if (std::abs(along) < k.box.L_m / 2.0 && std::abs(across) < k.box.W_m / 2.0) {
                nested = true;
                break;
            }
        }
        if (!nested) kept.push_back(std::move(c));
    }
    return kept;
}

/// Image-space connected components refined by depth: points of neighbouring pixels (within
/// radius_px, to hop small disparity holes) are linked when their 3D distance is below the
/// depth-grown clustering distance.
std::vector<Indices> image_components(const std::vector<Eigen::Vector3f>& pts,
                                      const std::vector<std::uint32_t>& pixels,
                                      const PixelGrid& grid, const ClusterOptions& co,
                                      int radius_px) {
    std::vector<long> at(static_cast<std::size_t>(grid.width_px) * grid.height_px, -1);
    for (std::size_t i = 0; i < pts.size(); ++i) at[pixels[i]] = static_cast<long>(i);
    std::vector<char> seen(pts.size(), 0);
    std::vector<Indices> out;
    for (std::size_t seed = 0; seed < pts.size(); ++seed) {
        if (seen[seed]) continue;
        seen[seed] = 1;
        Indices queue = {seed};
        for (std::size_t head = 0; head < queue.size(); ++head) {
            const std::size_t i = queue[head];
            const int u0 = static_cast<int>(pixels[i] % static_cast<std::uint32_t>(grid.width_px));
            const int v0 = static_cast<int>(pixels[i] / static_cast<std::uint32_t>(grid.width_px));
            for (int v = std::max(0, v0 - radius_px);
                 v <= std::min(grid.height_px - 1, v0 + radius_px); ++v) {
                for (int u = std::max(0, u0 - radius_px);
                     u <= std::min(grid.width_px - 1, u0 + radius_px); ++u) {
                    const long j = at[static_cast<std::size_t>(v) * grid.width_px + u];
                    if (j < 0 || seen[static_cast<std::size_t>(j)]) continue;
                    const auto& q = pts[static_cast<std::size_t>(j)];
                    const double link = co.distance_at(std::min(double{pts[i].z()}, double{q.z()}));
                    if (double{(pts[i] - q).squaredNorm()} > link * link) continue;
                    seen[static_cast<std::size_t>(j)] = 1;
                    queue.push_back(static_cast<std::size_t>(j));
                }
            }
        }
        out.push_back(std::move(queue));
    }
    return out;
}

/// Keeps the `max_entities` entities with the most points, largest first (stable).
void keep_largest(std::vector<scene_schema::Entity>& entities, int max_entities) {
    std::stable_sort(entities.begin(), entities.end(),
                     [](const auto& a, const auto& b) { return a.point_count > b.point_count; });
    if (entities.size() > static_cast<std::size_t>(max_entities)) {
        entities.resize(static_cast<std::size_t>(max_entities));
    }
}

/// Stuff entities: one box over each cluster, never split, fitted to the cluster's voxel
/// centroids weighted by their point counts (a stuff cluster costs its voxels, not its points);
/// each of `pts` stands for `step` points of the cloud (every step-th column taken).
std::vector<scene_schema::Entity> stuff_of_class(const ClassInfo& info,
                                                 const std::vector<Eigen::Vector3f>& pts,
                                                 std::size_t step, const ClassSettings& s,
                                                 const PendingGround& pending_ground,
                                                 const ClusterOptions& co,
                                                 const BoxFitOptions& fit) {
    const VoxelGrid voxels = voxelize(pts, s.voxel_m, s.voxel_doubling_depths());
    const std::vector<Indices> voxel_clusters = euclidean_clusters(voxels.centroid_m, co);
    const std::optional<GroundPlane>& ground = pending_ground.get();
    const std::size_t min_points = std::max<std::size_t>(static_cast<std::size_t>(s.min_points), 1);
    std::vector<scene_schema::Entity> out;
    std::vector<Eigen::Vector3f> centroids;
    std::vector<float> counts;
    for (const Indices& cluster : voxel_clusters) {
        std::size_t size = 0;
        for (std::size_t v : cluster) size += step * voxels.count[v];
        if (size < min_points) continue;
        centroids.clear();
        counts.clear();
        for (std::size_t v : cluster) {
            centroids.push_back(voxels.centroid_m[v]);
            counts.push_back(static_cast<float>(step * voxels.count[v]));
        }
        out.push_back(make_entity(info, fit_upright_box_weighted(centroids, counts, ground, fit),
                                  size, confidence_of(size, s), "instances"));
    }
    keep_largest(out, s.max_entities);
    return out;
}

/// Clustering and box-fit settings of a class.
struct ClassFit {
    ClusterOptions cluster;
    BoxFitOptions box;
};

ClassFit class_fit(const ClassSettings& s) {
    ClassFit f;
    f.cluster.distance_at_10m_m = s.cluster_distance_m;
    f.cluster.growth = s.cluster_growth;
    f.cluster.distance_max_m = s.cluster_distance_max_m;
    f.cluster.min_points = 1;
    if (s.thing && s.has_prior()) {
        f.box.prior_L_m = s.prior_L_m;
        f.box.prior_W_m = s.prior_W_m;
        f.box.prior_H_m = s.prior_H_m;
    }
    f.box.rest_on_ground = s.thing;
    return f;
}

/// The clusters of a thing class (point indices in point order).
std::vector<Indices> thing_clusters(const std::vector<Eigen::Vector3f>& pts,
                                    const std::vector<std::uint32_t>& pixels, const PixelGrid& grid,
                                    const ClassSettings& s, const ClusterOptions& co,
                                    const ExtractOptions& options) {
    if (options.clustering == "image" && grid.valid()) {
        return image_components(pts, pixels, grid, co, options.image_radius_px);
    }
    const VoxelGrid voxels = voxelize(pts, s.voxel_m, s.voxel_doubling_depths());
    return points_of(euclidean_clusters(voxels.centroid_m, co), voxels);
}

/// The candidates of thing cluster number `cluster`: its points without smear, fitted, split
/// when oversized (at most two levels: rows, then side by side) and refitted. Pieces cut at
/// clear gaps keep the cluster's shadow group (`cluster`); other pieces get groups of their
/// own, (cluster + 1) * 2^32 + k, unique over the class.
std::vector<Candidate> candidates_of_cluster(const std::vector<Eigen::Vector3f>& pts,
                                             Indices members, std::size_t cluster,
                                             const ClassSettings& s,
                                             const std::optional<GroundPlane>& ground,
                                             BoxFitOptions fit, const ExtractOptions& options) {
    std::vector<Candidate> candidates;
    members = drop_outliers(pts, members, s, ground, options.outlier_margin_m);
    std::size_t next_group = (cluster + 1) << 32;
    // Work items: points, split depth, shadow group, imposed heading.
    std::vector<std::tuple<Indices, int, std::size_t, std::optional<double>>> work = {
        {std::move(members), 0, cluster, std::nullopt}};
    while (!work.empty()) {
        auto [part, depth, group, yaw] = std::move(work.back());
        work.pop_back();
        // A piece of a row (cut at clear gaps or at a front-on row's pitch) is a thing
        // because the row is: half the minimum suffices for its sparse far end.
        const bool row_piece = depth > 0 && group == cluster;
        const auto min_points =
            static_cast<std::size_t>(row_piece ? s.min_points / 2 : s.min_points);
        if (part.size() < std::max<std::size_t>(min_points, 1)) continue;
        fit.yaw_rad = yaw;
        const OrientedBox box = fit_upright_box(gather(pts, part), ground, fit);
        if (depth < 2 && !yaw) {
            Split split = split_oversized(pts, part, box, s, ground, options);
            if (split.parts.size() > 1) {
                for (auto& piece : split.parts) {
                    work.emplace_back(std::move(piece), depth + 1,
                                      split.at_gaps ? group : next_group++, split.yaw_rad);
                }
                continue;
            }
        }
        // A thing whose points all lie near the ground is mislabelled road, not an object.
        if (s.prior_H_m > 0.0 && ground && box.H_m < options.min_height_fraction * s.prior_H_m) {
            continue;
        }
        Candidate c{box, std::move(part), 0.0, group};
        if (s.has_prior()) {
            c.fragment = c.members.size() < static_cast<std::size_t>(s.min_points) ||
                         height_spread(pts, c.members, ground) <
                             options.fragment_height_fraction * s.prior_H_m;
        }
        for (std::size_t i : c.members) {
            const double x = pts[i].x(), z = pts[i].z();
            c.range_m += std::sqrt(x * x + z * z);
        }
        c.range_m /= static_cast<double>(c.members.size());
        candidates.push_back(std::move(c));
    }
    return candidates;
}

/// The entities of a thing class from its clusters' candidates (in cluster order): shadows
/// and nested fragments suppressed, the largest kept.
std::vector<scene_schema::Entity> things_of_class(const ClassInfo& info,
                                                  std::vector<Candidate> candidates,
                                                  const std::vector<std::uint32_t>& pixels,
                                                  const PixelGrid& grid, const ClassSettings& s,
                                                  const ExtractOptions& options) {
    if (s.has_prior()) {
        candidates = suppress_shadows(std::move(candidates), pixels, grid, s.prior_W_m,
                                      options.shadow_fraction, options.shadow_radius_px);
    }
    candidates = suppress_nested(std::move(candidates));
    std::vector<scene_schema::Entity> out;
    for (const auto& c : candidates) {
        out.push_back(make_entity(info, c.box, c.members.size(), confidence_of(c.members.size(), s),
                                  "instances"));
    }
    keep_largest(out, s.max_entities);
    return out;
}

/// Threads kept between calls for the extractor's parallel parts: starting a thread costs tens
/// of microseconds, more right after the matcher, and a call started three. Not OpenCV's pool:
/// the task queue's workers block while they wait for running tasks, which would starve a
/// matcher running beside them on that pool (batch mode). A call offers work to helper threads
/// and runs it itself too, so it completes even when no helper is free.
class Helpers {
  public:
    static Helpers& instance() {
        static Helpers helpers;
        return helpers;
    }
    Helpers(const Helpers&) = delete;
    Helpers& operator=(const Helpers&) = delete;

    /// Runs `fn` (which must not throw) on this thread and on up to `extra` helper threads at
    /// once; returns when every started copy has returned. Copies not started by the time this
    /// thread's copy returns are withdrawn.
    void run(int extra, const std::function<void()>& fn) {
        Job job{&fn};
        {
            const std::lock_guard<std::mutex> lock(mutex_);
            while (static_cast<int>(threads_.size()) < extra) {
                threads_.emplace_back([this] { serve(); });
            }
            for (int i = 0; i < extra; ++i) offers_.push_back(&job);
        }
        wake_.notify_all();
        fn();
        std::unique_lock<std::mutex> lock(mutex_);
        offers_.erase(std::remove(offers_.begin(), offers_.end(), &job), offers_.end());
        done_.wait(lock, [&job] { return job.running == 0; });
    }

  private:
    struct Job {
        const std::function<void()>* fn;
        int running = 0;
    };
    Helpers() = default;
    ~Helpers() {
        {
            const std::lock_guard<std::mutex> lock(mutex_);
            stop_ = true;
        }
        wake_.notify_all();
        for (auto& t : threads_) t.join();
    }
    void serve() {
        std::unique_lock<std::mutex> lock(mutex_);
        for (;;) {
            wake_.wait(lock, [this] { return stop_ || !offers_.empty(); });
            if (stop_) return;
            Job* job = offers_.front();
            offers_.pop_front();
            ++job->running;
            lock.unlock();
            (*job->fn)();
            lock.lock();
            --job->running;
            done_.notify_all();
        }
    }
    std::mutex mutex_;
    std::condition_variable wake_, done_;
    std::deque<Job*> offers_;
    std::vector<std::thread> threads_;
    bool stop_ = false;
};

/// Runs tasks on a fixed number of threads. A running task may add tasks at the front, to run
/// before the ones queued: a class's cluster fits start as soon as its clustering is done, on
/// whichever thread is free, so that no thread is left alone with the largest class at the
/// end. The first exception stops the run (queued tasks are dropped) and is rethrown by run().
class TaskQueue {
  public:
    using Task = std::function<void()>;
    /// Queues a task at the back; before run() or from a running task.
    void push_back(Task task) {
        const std::lock_guard<std::mutex> lock(mutex_);
        queue_.push_back(std::move(task));
        wake_.notify_one();
    }
    /// Queues tasks at the front, in their order.
    void push_front(std::vector<Task> tasks) {
        const std::lock_guard<std::mutex> lock(mutex_);
        queue_.insert(queue_.begin(), std::make_move_iterator(tasks.begin()),
                      std::make_move_iterator(tasks.end()));
        wake_.notify_all();
    }
    /// Runs every task (those queued, and those they add) on `threads` threads, this one
    /// included; returns when all have run.
    void run(int threads) {
        Helpers::instance().run(threads - 1, [this] { work(); });
        if (failure_) std::rethrow_exception(failure_);
    }

  private:
    void work() {
        std::unique_lock<std::mutex> lock(mutex_);
        for (;;) {
            wake_.wait(lock, [this] { return !queue_.empty() || running_ == 0; });
            if (queue_.empty()) return;  // and nothing running that could add more
            Task task = std::move(queue_.front());
            queue_.pop_front();
            ++running_;
            lock.unlock();
            std::exception_ptr failure;
            try {
                task();
            } catch (...) {
                failure = std::current_exception();
            }
            lock.lock();
            --running_;
            if (failure) {
                if (!failure_) failure_ = failure;
                queue_.clear();
            }
            if (queue_.empty() && running_ == 0) wake_.notify_all();
        }
    }
    std::mutex mutex_;
    std::condition_variable wake_;
    std::deque<Task> queue_;
    int running_ = 0;
    std::exception_ptr failure_;
};

/// Entities of thing class `info` made on `queue`: clustered by this task, then one task per
/// cluster of at least min_points (largest first, at the front of the queue); the last of
/// them to finish makes the class's entities, from the candidates in cluster order, into `out`.
void queue_things_of_class(TaskQueue& queue, const ClassInfo& info,
                           const std::vector<Eigen::Vector3f>& pts,
                           const std::vector<std::uint32_t>& pixels, const PixelGrid& grid,
                           const ClassSettings& settings, const PendingGround& pending_ground,
                           const ExtractOptions& options, std::vector<scene_schema::Entity>& out) {
    struct Job {
        ClassSettings s;
        ClassFit fit;
        std::vector<Indices> clusters;
        std::vector<std::vector<Candidate>> candidates;  ///< per cluster
        std::atomic<std::size_t> left{0};                ///< clusters not fitted yet
    };
    auto job = std::make_shared<Job>();
    job->s = settings;
    job->fit = class_fit(settings);
    job->clusters = thing_clusters(pts, pixels, grid, settings, job->fit.cluster, options);
    job->candidates.resize(job->clusters.size());
    const auto finish = [&info, &pixels, &grid, &options, &out](Job& j) {
        std::vector<Candidate> all;
        for (auto& c : j.candidates) {
            all.insert(all.end(), std::make_move_iterator(c.begin()),
                       std::make_move_iterator(c.end()));
        }
        out = things_of_class(info, std::move(all), pixels, grid, j.s, options);
    };
    // One task per cluster with enough points, the largest first.
    std::vector<std::size_t> fitted;
    for (std::size_t c = 0; c < job->clusters.size(); ++c) {
        if (job->clusters[c].size() >= static_cast<std::size_t>(settings.min_points)) {
            fitted.push_back(c);
        }
    }
    if (fitted.empty()) {
        finish(*job);
        return;
    }
    std::stable_sort(fitted.begin(), fitted.end(), [&](std::size_t a, std::size_t b) {
        return job->clusters[a].size() > job->clusters[b].size();
    });
    job->left = fitted.size();
    std::vector<TaskQueue::Task> tasks;
    for (const std::size_t c : fitted) {
        tasks.emplace_back([job, c, finish, &pts, &pending_ground, &options] {
            job->candidates[c] = candidates_of_cluster(pts, std::move(job->clusters[c]), c, job->s,
                                                       pending_ground.get(), job->fit.box, options);
            if (--job->left == 0) finish(*job);
        });
    }
    queue.push_front(std::move(tasks));
}

/// Ground plane of the points of the ground classes (options.ground_classes).
std::optional<GroundPlane> fit_ground(const std::vector<std::vector<Eigen::Vector3f>>& per_class,
                                      const Palette& palette, const ExtractOptions& options) {
    std::vector<Eigen::Vector3f> ground_pts;
    for (std::size_t k = 0; k < palette.classes.size(); ++k) {
        const auto& names = options.ground_classes;
        if (std::find(names.begin(), names.end(), palette.classes[k].name) != names.end()) {
            ground_pts.insert(ground_pts.end(), per_class[k].begin(), per_class[k].end());
        }
    }
    return fit_ground_plane(ground_pts, options.ground);
}

/// Fewest points per thread when the cloud is split by class (below, threads cost more than
/// they save).
constexpr std::size_t kMinChunkPoints = 32768;

/// Calls body(c, first, last) for `chunks` contiguous ranges [first, last) of [0, n), taken in
/// turn by this thread and up to chunks - 1 helpers; rethrows the first exception.
template <typename Body>
void for_each_chunk(std::size_t n, std::size_t chunks, Body&& body) {
    const auto bound = [&](std::size_t c) { return n / chunks * c + std::min(c, n % chunks); };
    std::atomic<std::size_t> next{0};
    std::mutex failure_mutex;
    std::exception_ptr failure;
    Helpers::instance().run(static_cast<int>(chunks) - 1, [&] {
        for (std::size_t c = next++; c < chunks; c = next++) {
            try {
                body(c, bound(c), bound(c + 1));
            } catch (...) {
                const std::lock_guard<std::mutex> lock(failure_mutex);
                if (!failure) failure = std::current_exception();
            }
        }
    });
    if (failure) std::rethrow_exception(failure);
}

}  // namespace

void ExtractOptions::validate() const {
    if (method != "instances" && method != "centroid" && method != "average" &&
        method != "variance") {
        throw std::invalid_argument(
            "method: must be instances, centroid, average or variance (got '" + method + "')");
    }
    classes.validate();
    ground.validate();
    if (!(max_range_m > 0.0)) throw std::invalid_argument("max_range_m: must be > 0");
    if (clustering != "euclidean" && clustering != "image") {
        throw std::invalid_argument("clustering: must be euclidean or image (got '" + clustering +
                                    "')");
    }
    if (image_radius_px < 1) throw std::invalid_argument("image_radius_px: must be >= 1");
    if (!(outlier_margin_m >= 0.0)) throw std::invalid_argument("outlier_margin_m: must be >= 0");
    if (!(shadow_fraction > 0.0 && shadow_fraction <= 1.0)) {
        throw std::invalid_argument("shadow_fraction: must be in (0, 1]");
    }
    if (shadow_radius_px < 0) throw std::invalid_argument("shadow_radius_px: must be >= 0");
    if (!(fragment_height_fraction >= 0.0 && fragment_height_fraction <= 1.0)) {
        throw std::invalid_argument("fragment_height_fraction: must be in [0, 1]");
    }
    if (!(min_height_fraction >= 0.0 && min_height_fraction < 1.0)) {
        throw std::invalid_argument("min_height_fraction: must be in [0, 1)");
    }
    if (!(row_low_fraction >= 0.0 && row_low_fraction < 1.0)) {
        throw std::invalid_argument("row_low_fraction: must be in [0, 1)");
    }
    if (!(row_low_extent_m > 0.0)) throw std::invalid_argument("row_low_extent_m: must be > 0");
    if (!(row_gap_m >= 0.0)) throw std::invalid_argument("row_gap_m: must be >= 0");
    if (threads < 1) throw std::invalid_argument("threads: must be >= 1");
    if (!(stuff_on_thing_fraction > 0.0 && stuff_on_thing_fraction <= 1.0)) {
        throw std::invalid_argument("stuff_on_thing_fraction: must be in (0, 1]");
    }
}

ClassSelection class_selection(const Palette& palette, const ExtractOptions& options) {
    ClassSelection selection;
    selection.max_depth_m = options.max_range_m;
    for (const ClassInfo& info : palette.classes) {
        const ClassSettings s = options.classes.find(info.name);
        selection.column_mask.push_back(static_cast<std::uint32_t>(s.column_step) - 1);
        selection.keep_pixels.push_back(s.thing ? 1 : 0);
    }
    return selection;
}

ClassPoints points_by_class(const LabeledCloud& cloud, const ClassSelection& selection,
                            int threads) {
    if (cloud.class_index.size() != cloud.xyz_m.size()) {
        throw std::invalid_argument("cloud: class_index and xyz_m differ in size");
    }
    if (selection.keep_pixels.size() != selection.column_mask.size()) {
        throw std::invalid_argument("selection: column_mask and keep_pixels differ in size");
    }
    const std::size_t classes = selection.column_mask.size();
    ClassPoints out;
    out.cloud_points = cloud.size();
    auto& per_class = out.xyz_m;
    auto& per_class_pixels = out.pixel;
    per_class.resize(classes);
    per_class_pixels.resize(classes);
    // Split on `chunks` threads over contiguous point ranges (each chunk writes its points of a
    // class after the previous chunks' ones, so the order is the points' order): count, size,
    // write, then close the gaps the range check left.
    const std::size_t chunks = std::clamp<std::size_t>(
        cloud.size() / kMinChunkPoints, 1, static_cast<std::size_t>(std::max(threads, 1)));
    const bool has_pixels = cloud.pixel.size() == cloud.size();
    // Columns are thinned only when the cloud knows its pixels.
    std::vector<std::uint32_t> column_mask(classes, 0);
    if (has_pixels && cloud.width_px > 0) column_mask = selection.column_mask;
    out.weight.resize(classes);
    for (std::size_t k = 0; k < classes; ++k) out.weight[k] = std::size_t{column_mask[k]} + 1;
    const auto width = static_cast<std::uint32_t>(std::max(cloud.width_px, 1));
    // Column of pixel p, for pixels mostly in increasing order: the row's first pixel is
    // found by a division only when p leaves the row.
    const auto column_of = [width](std::uint32_t p, std::uint32_t& row_start) {
        if (p - row_start >= width) row_start = p / width * width;
        return p - row_start;
    };
    const auto taken = [&](std::size_t i, std::uint16_t k, std::uint32_t& row_start) {
        return column_mask[k] == 0 || (column_of(cloud.pixel[i], row_start) & column_mask[k]) == 0;
    };
    std::vector<std::vector<std::size_t>> start(chunks, std::vector<std::size_t>(classes, 0));
    std::vector<std::uint32_t> last_pixel(chunks, 0);
    for_each_chunk(cloud.size(), chunks, [&](std::size_t c, std::size_t first, std::size_t last) {
        // Every point of each class (an upper bound once the columns are thinned).
        auto& size = start[c];
        for (std::size_t i = first; i < last; ++i) {
            const auto k = cloud.class_index[i];
            if (k < classes) ++size[k];
        }
        for (std::size_t i = first; has_pixels && i < last; ++i) {
            last_pixel[c] = std::max(last_pixel[c], cloud.pixel[i]);
        }
    });
    const bool grid = has_pixels && cloud.width_px > 0 && cloud.height_px > 0 &&
                      *std::max_element(last_pixel.begin(), last_pixel.end()) <
                          static_cast<std::uint64_t>(cloud.width_px) * cloud.height_px;
    if (grid) {
        out.width_px = cloud.width_px;
        out.height_px = cloud.height_px;
    }
    // Sized for every point of the class, written by index, then cut to the points kept.
    for (std::size_t k = 0; k < classes; ++k) {
        std::size_t total = 0;
        for (std::size_t c = 0; c < chunks; ++c) total += std::exchange(start[c][k], total);
        per_class[k].resize(total);
        if (selection.keep_pixels[k]) per_class_pixels[k].resize(total);
    }
    std::vector<std::vector<std::size_t>> end = start;
    const double max_depth = selection.max_depth_m;
    for_each_chunk(cloud.size(), chunks, [&](std::size_t c, std::size_t first, std::size_t last) {
        auto& at = end[c];
        std::uint32_t row_start = 0;
        for (std::size_t i = first; i < last; ++i) {
            const auto k = cloud.class_index[i];
            const auto& p = cloud.xyz_m[i];
            if (k >= classes || !taken(i, k, row_start)) continue;
            if (!(p.z() > 0.0f && double{p.z()} < max_depth) || !p.allFinite()) continue;
            if (selection.keep_pixels[k]) per_class_pixels[k][at[k]] = grid ? cloud.pixel[i] : 0;
            per_class[k][at[k]++] = p;
        }
    });
    for (std::size_t k = 0; k < classes; ++k) {
        std::size_t kept = end[0][k];
        for (std::size_t c = 1; c < chunks; ++c) {
            const auto from = static_cast<std::ptrdiff_t>(start[c][k]);
            const auto to = static_cast<std::ptrdiff_t>(end[c][k]);
            std::copy(per_class[k].begin() + from, per_class[k].begin() + to,
                      per_class[k].begin() + static_cast<std::ptrdiff_t>(kept));
            if (selection.keep_pixels[k]) {
                std::copy(per_class_pixels[k].begin() + from, per_class_pixels[k].begin() + to,
                          per_class_pixels[k].begin() + static_cast<std::ptrdiff_t>(kept));
            }
            kept += end[c][k] - start[c][k];
        }
        per_class[k].resize(kept);
        if (selection.keep_pixels[k]) per_class_pixels[k].resize(kept);
    }
    return out;
}

scene_schema::EntityDocument extract_entities(const LabeledCloud& cloud, const Palette& palette,
                                              const StereoCamera& camera,
                                              const ExtractOptions& options) {
    static_cast<void>(camera);  // not needed by the current extractors (see extract.hpp)
    options.validate();
    return extract_entities(
        points_by_class(cloud, class_selection(palette, options), options.threads), palette,
        options);
}

scene_schema::EntityDocument extract_entities(const ClassPoints& points, const Palette& palette,
                                              const ExtractOptions& options) {
    options.validate();
    if (points.xyz_m.size() != palette.classes.size() ||
        points.pixel.size() != palette.classes.size() ||
        points.weight.size() != palette.classes.size()) {
        throw std::invalid_argument("points: not one entry per palette class");
    }
    std::vector<char> is_thing(palette.classes.size(), 0);
    for (std::size_t k = 0; k < palette.classes.size(); ++k) {
        is_thing[k] = options.classes.find(palette.classes[k].name).thing ? 1 : 0;
        if (is_thing[k] && points.pixel[k].size() != points.xyz_m[k].size()) {
            throw std::invalid_argument("points: no pixels for thing class '" +
                                        palette.classes[k].name + "'");
        }
    }
    const auto& per_class = points.xyz_m;
    const auto& per_class_pixels = points.pixel;
    const auto& step = points.weight;
    const PixelGrid grid{points.width_px, points.height_px};

    // The ground plane is the first task, fitted beside the clustering of the classes (which
    // does not need it); a class waits for it once clustered. Thing points cost about four
    // times stuff points (smear removal, splits, refits): the costliest classes start first,
    // and a thing class's clusters are fitted as tasks of their own, ahead of the queued
    // classes, so that both threads share the largest class.
    std::promise<std::optional<GroundPlane>> ground_promise;
    const PendingGround pending_ground = ground_promise.get_future().share();
    std::vector<double> cost(per_class.size());
    for (std::size_t k = 0; k < per_class.size(); ++k) {
        cost[k] = static_cast<double>(per_class[k].size()) * (is_thing[k] ? 4.0 : 1.0);
    }
    std::vector<std::vector<scene_schema::Entity>> made(palette.classes.size());
    std::vector<std::size_t> order(per_class.size());
    for (std::size_t k = 0; k < order.size(); ++k) order[k] = k;
    std::stable_sort(order.begin(), order.end(),
                     [&](std::size_t a, std::size_t b) { return cost[a] > cost[b]; });
    TaskQueue queue;
    queue.push_back([&] {
        try {
            ground_promise.set_value(options.method == "instances"
                                         ? fit_ground(per_class, palette, options)
                                         : std::nullopt);
        } catch (...) {
            ground_promise.set_exception(std::current_exception());
            throw;
        }
    });
    for (const std::size_t k : order) {
        const ClassInfo& info = palette.classes[k];
        const ClassSettings s = options.classes.find(info.name);
        const auto& pts = per_class[k];
        if (!s.entity || pts.size() * step[k] < static_cast<std::size_t>(s.min_points)) {
            continue;
        }
        queue.push_back([&, k, s] {
            if (options.method == "instances" && s.thing) {
                queue_things_of_class(queue, info, pts, per_class_pixels[k], grid, s,
                                      pending_ground, options, made[k]);
            } else if (options.method == "instances") {
                const ClassFit fit = class_fit(s);
                made[k] =
                    stuff_of_class(info, pts, step[k], s, pending_ground, fit.cluster, fit.box);
            } else {
                OrientedBox box;
                if (options.method == "centroid") {
                    const Eigen::Vector3d size =
                        s.has_prior() ? Eigen::Vector3d(s.prior_L_m, s.prior_H_m, s.prior_W_m)
                                      : Eigen::Vector3d(1.0, 1.0, 1.0);
                    box = centroid_box(pts, size);
                } else if (options.method == "average") {
                    box = average_box(pts);
                } else {
                    box = variance_box(pts);
                }
                const std::size_t n = pts.size() * step[k];
                made[k].push_back(make_entity(info, box, n, confidence_of(n, s), options.method));
            }
        });
    }
    queue.run(options.threads);
    scene_schema::EntityDocument doc;
    if (const std::optional<GroundPlane>& ground = pending_ground.get()) {
        doc.extra["ground_plane"] = {
            {"normal", {ground->normal.x(), ground->normal.y(), ground->normal.z()}},
            {"d", ground->d},
            {"camera_height_m", ground->camera_height_m()},
            {"inliers", ground->inliers}};
    }
    if (options.method == "instances" && options.stuff_on_thing_fraction < 1.0) {
        std::vector<scene_schema::Entity> things;
        for (std::size_t k = 0; k < made.size(); ++k) {
            if (is_thing[k]) things.insert(things.end(), made[k].begin(), made[k].end());
        }
        const std::vector<Footprint> footprints = footprints_of(things);
        for (std::size_t k = 0; k < made.size(); ++k) {
            if (is_thing[k]) continue;
            auto& list = made[k];
            list.erase(std::remove_if(list.begin(), list.end(),
                                      [&](const scene_schema::Entity& e) {
                                          return footprint_share_inside(e, footprints) >
                                                 options.stuff_on_thing_fraction;
                                      }),
                       list.end());
        }
    }
    for (std::size_t k = 0; k < made.size(); ++k) {
        std::string stem = palette.classes[k].name;
        std::replace(stem.begin(), stem.end(), ' ', '-');
        for (std::size_t n = 0; n < made[k].size(); ++n) {
            made[k][n].id = stem + "-" + std::to_string(n + 1);
            doc.entities.push_back(std::move(made[k][n]));
        }
    }
    return doc;
}

}  // namespace cloud_analysis
