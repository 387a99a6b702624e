#include "cloud_analysis/entities/things.hpp"

#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstdint>
#include <iterator>
#include <limits>
#include <memory>
#include <tuple>
#include <unordered_map>
#include <unordered_set>
#include <utility>

#include "cloud_analysis/entities/cuts.hpp"
#include "cloud_analysis/entities/image_components.hpp"
#include "cloud_analysis/entities/row_split.hpp"
#include "cloud_analysis/entities/smear.hpp"
#include "cloud_analysis/entities/suppression.hpp"

namespace cloud_analysis::instances {
namespace {

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

/// Most points a thing's own box reads once its heading is set: its extents are quantiles,
/// which a near car's 30,000 points fix no better than 8,000.
constexpr std::size_t kMaxFitPoints = 8192;

/// A thing's points (in point order) thinned to what its own box reads: all of them, or every
/// s-th (the least s that leaves at most kMaxFitPoints), spread evenly over its pixels.
void thin_to_fit_sample(std::vector<Eigen::Vector3f>& member_pts) {
    const std::size_t n = member_pts.size();
    const std::size_t step = std::max<std::size_t>(1, (n + kMaxFitPoints - 1) / kMaxFitPoints);
    if (step == 1) return;
    std::size_t kept = 0;
    for (std::size_t k = 0; k < n; k += step) member_pts[kept++] = member_pts[k];
    member_pts.resize(kept);
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

/// Whether a thing's box (resting on the ground) is too low to be one: points all near the
/// ground are mislabelled road, and a thing of the size family whose top stays under
/// family_min_height_m is a piece of something low.
bool too_low(const OrientedBox& box, const ClassSettings& s,
             const std::optional<GroundPlane>& ground, const ExtractOptions& options) {
    if (!ground) return false;
    if (s.prior_H_m > 0.0 && box.H_m < options.min_height_fraction * s.prior_H_m) return true;
    return s.name == options.family_class && box.H_m < options.family_min_height_m;
}

/// The fit of a thing's own box once no split is left: the splits read the box as fitted; the
/// thing's own box trims its near end further along the viewing ray and takes its extents over
/// seen surface (a side seen along the ray holds few points per metre at its far end).
BoxFitOptions own_box_fit(const BoxFitOptions& fit, const ExtractOptions& options) {
    BoxFitOptions final_fit = fit;
    final_fit.near_trim_fraction = std::max(fit.trim_fraction, options.near_trim_fraction);
    final_fit.area_weighted_extents = options.area_weighted_extents;
    return final_fit;
}

/// The thing's own box (own_box_fit) of its points, `box` when that fit changes nothing; on the
/// footprint axis `box`'s fit chose (own_box_fit changes only how the extents are trimmed).
OrientedBox own_box(const std::vector<Eigen::Vector3f>& member_pts, const OrientedBox& box,
                    const FootprintAxis& axis, const BoxFitOptions& fit,
                    const BoxFitOptions& final_fit, const std::optional<GroundPlane>& ground) {
    if (final_fit.near_trim_fraction > fit.near_trim_fraction || final_fit.area_weighted_extents) {
        return fit_upright_box_on_axis(member_pts, ground, final_fit, axis);
    }
    return box;
}

/// A candidate's size family (a van's length prior when it is as tall as one, its box as
/// fitted being `fitted_H_m` tall), the far end of its side from its pixel columns, its
/// fragment flag and its mean range.
void complete_candidate(Candidate& c, const std::vector<Eigen::Vector3f>& pts,
                        const std::vector<Eigen::Vector3f>& member_pts, double fitted_H_m,
                        const BoxFitOptions& final_fit, const ClassSettings& s,
                        const std::optional<GroundPlane>& ground, const ExtractOptions& options,
                        const std::optional<std::array<bool, 2>>& own_outline = std::nullopt) {
    if (!options.family_class.empty() && s.name == options.family_class) {
        // A van shows its height: its hidden length is a van's, not a car's.
        c.subclass = "car";
        if (fitted_H_m >= options.van_min_height_m) {
            BoxFitOptions van = final_fit;
            van.prior_L_m = options.van_prior_L_m;
            van.prior_W_m = options.van_prior_W_m;
            c.box = fit_upright_box(member_pts, ground, van);
            c.subclass = "van";
        }
    }
    if (s.name == options.family_class && options.far_column_length_fraction > 0.0) {
        // A side seen along the viewing ray: its far end where its pixels end in the image.
        const double prior = c.subclass == "van" ? options.van_prior_L_m : s.prior_L_m;
        c.box = far_end_to_columns(c.box, member_pts,
                                   std::max(c.box.L_m, options.far_column_length_fraction * prior),
                                   own_outline);
    }
    if (c.subclass == "van" && c.box.L_m > options.van_max_L_m) {
        // Longer than any van: the piece holds the end of the thing before it in its row
        // too (a row's cut at a van's windscreen foot, where the glass matches sparsely,
        // leaves the van's front to the piece beyond). The van keeps its far end.
        c.box = with_length(c.box, options.van_prior_L_m, true);
    }
    if (s.has_prior()) {
        c.fragment =
            c.members.size() < static_cast<std::size_t>(s.min_points) ||
            height_spread(pts, c.members, ground) < options.fragment_height_fraction * s.prior_H_m;
    }
    for (std::size_t i : c.members) {
        const double x = pts[i].x(), z = pts[i].z();
        c.range_m += std::sqrt(x * x + z * z);
    }
    c.range_m /= static_cast<double>(c.members.size());
}

/// A piece to fit: its points, split depth, shadow group, imposed heading, and whether it is
/// a piece of a row's partition (not cut along the row again).
using WorkItem = std::tuple<Indices, int, std::size_t, std::optional<double>, bool>;

/// What the steps of candidates_of_cluster share: its inputs, the box fit (each piece sets
/// its heading and truncation), the work items left, the next group number and the
/// candidates made.
struct ClusterPieces {
    const std::vector<Eigen::Vector3f>& pts;
    const std::vector<std::uint32_t>& pixels;
    const PixelGrid& grid;
    std::size_t cluster;
    const ClassSettings& s;
    const std::optional<GroundPlane>& ground;
    const ExtractOptions& options;
    BoxFitOptions fit;
    std::size_t next_group;
    std::vector<WorkItem> work;
    std::vector<Candidate> candidates;

    /// Queues the pieces of `behind` (points of the cluster farther than a thing behind its
    /// nearest points) clustered again on their own, each in a group of its own.
    void queue_behind(const Indices& behind, const ClusterOptions& co) {
        std::vector<Eigen::Vector3f> far_pts;
        std::vector<std::uint32_t> far_pixels;
        for (std::size_t i : behind) {
            far_pts.push_back(pts[i]);
            if (pixels.size() >= pts.size()) far_pixels.push_back(pixels[i]);
        }
        for (const Indices& c : thing_clusters(far_pts, far_pixels, grid, s, co, options)) {
            if (c.size() < static_cast<std::size_t>(s.min_points)) continue;
            Indices piece;
            for (std::size_t k : c) piece.push_back(behind[k]);
            piece = drop_outliers(pts, piece, s, ground, options.outlier_margin_m);
            work.emplace_back(std::move(piece), 0, next_group++, std::nullopt, false);
        }
    }

    /// Queues the pieces of a split one level deeper; false when it did not split.
    bool queue_pieces(Split split, int depth, std::size_t group, bool row_piece) {
        if (split.parts.empty() || (split.parts.size() < 2 && !split.row_pieces)) return false;
        for (auto& piece : split.parts) {
            work.emplace_back(std::move(piece), depth + 1, split.at_gaps ? group : next_group++,
                              split.yaw_rad, split.row_pieces || row_piece);
        }
        return true;
    }

    /// Fits the work items until none is left: each one is split again when oversized or made
    /// a candidate.
    void fit_pieces() {
        while (!work.empty()) {
            auto [part, depth, group, yaw, in_row] = std::move(work.back());
            work.pop_back();
            // A piece of a row (cut at clear gaps, at a front-on row's pitch, or by the row's
            // partition where every cut has evidence) is a thing because the row is: half the
            // minimum suffices for its sparse far end.
            const bool row_piece = depth > 0 && group == cluster;
            const auto min_points =
                static_cast<std::size_t>(row_piece ? s.min_points / 2 : s.min_points);
            if (part.size() < std::max<std::size_t>(min_points, 1)) continue;
            fit.yaw_rad = yaw;
            fit.truncation_xz = truncation_point(pts, pixels, grid, part);
            std::vector<Eigen::Vector3f> member_pts = gather(pts, part);
            FootprintAxis axis;
            const OrientedBox box = fit_upright_box(member_pts, ground, fit, axis);
            if (depth < 3 && !yaw &&
                queue_pieces(split_oversized(pts, part, box, s, ground, options,
                                             fit.truncation_xz.has_value(), in_row),
                             depth, group, in_row)) {
                continue;
            }
            // A thing whose points all lie near the ground is mislabelled road, not an object.
            if (too_low(box, s, ground, options)) continue;
            Candidate c;
            c.members = std::move(part);
            c.group = group;
            const BoxFitOptions final_fit = own_box_fit(fit, options);
            thin_to_fit_sample(member_pts);
            c.box = own_box(member_pts, box, axis, fit, final_fit, ground);
            // The thing's own box can come out longer than the box the splits read (its near end
            // trimmed along the ray, its extents over seen surface): still more than one.
            if (depth < 4 && !yaw && s.has_prior() && c.box.L_m > s.split_factor * s.prior_L_m &&
                queue_pieces(split_oversized(pts, c.members, c.box, s, ground, options,
                                             fit.truncation_xz.has_value(), in_row),
                             depth, group, in_row)) {
                continue;
            }
            complete_candidate(c, pts, member_pts, box.H_m, final_fit, s, ground, options);
            candidates.push_back(std::move(c));
        }
    }
};

/// The candidates of thing cluster number `cluster`: its points without smear, fitted, split
/// when oversized (at most three levels: side by side, rows, their pieces) and refitted. Pieces cut
/// at clear gaps keep the cluster's shadow group (`cluster`); other pieces get groups of their own,
/// (cluster + 1) * 2^32 + k, unique over the class. The points the smear filter drops are
/// clustered again: a thing behind another, joined to it by smear, is a cluster of its own.
std::vector<Candidate> candidates_of_cluster(const std::vector<Eigen::Vector3f>& pts,
                                             const std::vector<std::uint32_t>& pixels,
                                             const PixelGrid& grid, Indices members,
                                             std::size_t cluster, const ClassSettings& s,
                                             const ClassFit& class_fit,
                                             const std::optional<GroundPlane>& ground,
                                             const ExtractOptions& options) {
    ClusterPieces p{
        pts, pixels, grid, cluster, s, ground, options, class_fit.box, (cluster + 1) << 32, {}, {}};
    p.fit.disparity_fb_px_m = grid.border.fb_px_m;
    Indices behind;
    Indices on_edge;
    members = off_depth_edges(pixels, grid, std::move(members), s, on_edge);
    members = drop_outliers(pts, members, s, ground, options.outlier_margin_m, &behind);
    p.work = {{std::move(members), 0, cluster, std::nullopt, false}};
    if (behind.size() >= static_cast<std::size_t>(s.min_points)) {
        // What lies farther than a thing behind the nearest points of the cluster is smear or
        // another thing behind it, joined to it by smear: clustered again on its own, each
        // piece is a thing of its own (shadow suppression then drops the smear).
        p.queue_behind(behind, class_fit.cluster);
    }
    p.fit_pieces();
    give_back_edge_points(pts, on_edge, p.candidates);
    // Two faint pieces of a row end to end are one thing cut in two (a car behind a van, its
    // first metre left to the van's piece); joined, they are fitted as one, not split again.
    std::vector<Indices> joined = join_faint_pieces(pts, p.candidates, s, options);
    if (!joined.empty()) {
        for (Indices& part : joined) {
            p.work.emplace_back(std::move(part), 4, cluster, std::nullopt, false);
        }
        p.fit_pieces();
    }
    return std::move(p.candidates);
}

/// The members in the largest of their clusters (thing_clusters): an object's surface is
/// connected, and those of its pixels that took another surface's disparity lie apart from it.
/// All of them when that cluster has fewer than min_points.
Indices largest_piece(const std::vector<Eigen::Vector3f>& pts,
                      const std::vector<std::uint32_t>& pixels, const PixelGrid& grid,
                      const Indices& members, const ClassSettings& s, const ClusterOptions& co,
                      const ExtractOptions& options) {
    std::vector<std::uint32_t> member_pixels;
    for (std::size_t i = 0; pixels.size() >= pts.size() && i < members.size(); ++i) {
        member_pixels.push_back(pixels[members[i]]);
    }
    const std::vector<Indices> pieces =
        thing_clusters(gather(pts, members), member_pixels, grid, s, co, options);
    const auto largest =
        std::max_element(pieces.begin(), pieces.end(),
                         [](const Indices& a, const Indices& b) { return a.size() < b.size(); });
    if (largest == pieces.end() || largest->size() < static_cast<std::size_t>(s.min_points)) {
        return members;
    }
    Indices kept;
    for (std::size_t k : *largest) kept.push_back(members[k]);
    std::sort(kept.begin(), kept.end());
    return kept;
}

/// The members without `drop` (sorted), sorted; the members as they are when fewer than
/// `min_left` would remain.
Indices without(Indices members, const Indices& drop, std::size_t min_left) {
    if (drop.empty() || members.size() < drop.size() + min_left) return members;
    std::sort(members.begin(), members.end());
    Indices kept;
    std::set_difference(members.begin(), members.end(), drop.begin(), drop.end(),
                        std::back_inserter(kept));
    return kept;
}

/// The candidate of one object of the instance image: its points off depth edges and without
/// the smear behind it, fitted once and never split (the instance image says where it ends).
std::vector<Candidate> candidates_of_instance(const std::vector<Eigen::Vector3f>& pts,
                                              const std::vector<std::uint32_t>& pixels,
                                              const PixelGrid& grid, Indices members,
                                              std::size_t cluster, std::uint32_t instance,
                                              const ClassSettings& s, const ClassFit& class_fit,
                                              const std::optional<GroundPlane>& ground,
                                              const ExtractOptions& options) {
    BoxFitOptions fit = class_fit.box;
    fit.disparity_fb_px_m = grid.border.fb_px_m;
    fit.short_face_is_end = true;
    Indices on_edge;
    members = off_depth_edges(pixels, grid, std::move(members), s, on_edge);
    const auto min_points = static_cast<std::size_t>(std::max(s.min_points, 1));
    // Something standing in front of it inside its outline is not its surface.
    members = without(std::move(members), occluders_inside(pts, pixels, grid, members), min_points);
    const bool family = !options.family_class.empty() && s.name == options.family_class;
    if (s.has_prior()) {
        // The longest thing of the class (a van for the size-family class) spans its diagonal.
        const double L = family ? std::max(s.prior_L_m, options.van_prior_L_m) : s.prior_L_m;
        const double W = family ? std::max(s.prior_W_m, options.van_prior_W_m) : s.prior_W_m;
        members = densest_range_window(pts, members, std::hypot(L, W) + options.outlier_margin_m,
                                       static_cast<std::size_t>(s.min_points));
    }
    members = largest_piece(pts, pixels, grid, members, s, class_fit.cluster, options);
    members = drop_outliers(pts, members, s, ground, options.outlier_margin_m);
    if (members.size() < min_points) return {};
    fit.truncation_xz = truncation_point(pts, pixels, grid, members);
    // The image sides (left, right) where the outline is the object's own: not at the image's
    // edge, nothing nearer beyond it; there its far end is seen, and its length may be shorter
    // than the class's prior.
    std::array<bool, 2> cut = {true, true};
    if (!fit.truncation_xz) {
        Indices bleed;
        if (const auto hidden = occlusion_cut(pts, pixels, grid, members, instance, &bleed, &cut)) {
            fit.truncation_xz = hidden->xz;
            fit.truncation_side = hidden->side;
            // Pixels past its outline that took the nearer thing's depth are not its surface.
            members = without(std::move(members), bleed, min_points);
        }
    }
    std::vector<Eigen::Vector3f> member_pts = gather(pts, members);
    FootprintAxis axis;
    const OrientedBox box = fit_upright_box(member_pts, ground, fit, axis);
    // Points all near the ground are no object, whatever the image says.
    if (too_low(box, s, ground, options)) return {};
    Candidate c;
    c.members = std::move(members);
    c.group = cluster;
    c.instance = instance;
    const BoxFitOptions final_fit = own_box_fit(fit, options);
    thin_to_fit_sample(member_pts);
    c.box = own_box(member_pts, box, axis, fit, final_fit, ground);
    complete_candidate(c, pts, member_pts, box.H_m, final_fit, s, ground, options,
                       std::array<bool, 2>{!cut[0], !cut[1]});
    // Longer than any thing of its class, the box holds range smear behind the face it shows
    // (far away a pixel of disparity spans metres): the face is kept, the class's length
    // completes it, as for a thing whose far end is hidden.
    const bool van = c.subclass == "van";
    const double max_L_m = van ? options.van_max_L_m : s.split_factor * s.prior_L_m;
    if (s.has_prior() && c.box.L_m > max_L_m) {
        c.box = with_length(c.box, van ? options.van_prior_L_m : s.prior_L_m, false);
    }
    std::vector<Candidate> out;
    out.push_back(std::move(c));
    give_back_edge_points(pts, on_edge, out);
    return out;
}

/// The clusters of a thing class: with an instance image, one per object id among its points
/// (in the order of their first points), then the clusters (thing_clusters) of the points
/// without one; `instance` receives each cluster's object id, 0 for the clustered ones.
std::vector<Indices> clusters_of_class(const std::vector<Eigen::Vector3f>& pts,
                                       const std::vector<std::uint32_t>& pixels,
                                       const PixelGrid& grid, const ClassSettings& s,
                                       const ClusterOptions& co, const ExtractOptions& options,
                                       std::vector<std::uint32_t>& instance) {
    if (grid.instance_id == nullptr || pixels.size() < pts.size()) {
        std::vector<Indices> out = thing_clusters(pts, pixels, grid, s, co, options);
        instance.assign(out.size(), 0);
        return out;
    }
    const std::vector<std::uint32_t>& ids = *grid.instance_id;
    std::unordered_map<std::uint32_t, std::size_t> slot;
    std::vector<Indices> out;
    Indices rest;
    instance.clear();
    for (std::size_t i = 0; i < pts.size(); ++i) {
        const std::uint32_t id = ids[pixels[i]];
        if (id == 0) {
            rest.push_back(i);
            continue;
        }
        const auto [it, fresh] = slot.emplace(id, out.size());
        if (fresh) {
            out.emplace_back();
            instance.push_back(id);
        }
        out[it->second].push_back(i);
    }
    if (rest.empty()) return out;
    std::vector<std::uint32_t> rest_pixels;
    rest_pixels.reserve(rest.size());
    for (std::size_t i : rest) rest_pixels.push_back(pixels[i]);
    for (const Indices& c : thing_clusters(gather(pts, rest), rest_pixels, grid, s, co, options)) {
        Indices members;
        members.reserve(c.size());
        for (std::size_t k : c) members.push_back(rest[k]);
        out.push_back(std::move(members));
        instance.push_back(0);
    }
    return out;
}

/// The entities of a thing class from its clusters' candidates (in cluster order): shadows,
/// nested fragments and things seen over too little of their prior face suppressed, the largest
/// kept.
std::vector<scene_schema::Entity> things_of_class(const ClassInfo& info,
                                                  std::vector<Candidate> candidates,
                                                  const std::vector<Eigen::Vector3f>& pts,
                                                  const std::vector<std::uint32_t>& pixels,
                                                  const PixelGrid& grid, const ClassSettings& s,
                                                  const ExtractOptions& options) {
    // An object of the instance image is one thing as the image says: no suppression rule
    // (shadows, strips, nesting, faint faces) drops it, though it may drop clustered pieces.
    std::vector<Candidate> exact;
    for (const Candidate& c : candidates) {
        if (c.instance != 0) exact.push_back(c);
    }
    if (s.has_prior()) {
        // Widths are counted in points a row: one for every point_lattice_px pixels.
        const double lattice = options.point_lattice_px;
        candidates =
            drop_strips(std::move(candidates), pixels, grid, options.min_width_px / lattice);
        candidates = drop_strips_beside(std::move(candidates), pixels, grid,
                                        options.strip_beside_width_px / lattice,
                                        options.shadow_radius_px, options.strip_beside_gap_m);
        candidates = suppress_shadows(std::move(candidates), pixels, grid, s.prior_W_m,
                                      options.shadow_fraction, options.shadow_radius_px);
    }
    candidates = suppress_nested(std::move(candidates));
    if (const double min_m2 = min_seen_area_m2(s, options); min_m2 > 0.0) {
        // Seen area at the points' own depths: a box completed beyond the image's edge lies
        // nearer than the points it holds, one completed away from the camera farther.
        candidates.erase(std::remove_if(candidates.begin(), candidates.end(),
                                        [&](const Candidate& c) {
                                            return c.instance == 0 &&
                                                   thing_seen_area_m2(pts, c.members, options) <
                                                       min_m2;
                                        }),
                         candidates.end());
    }
    if (!exact.empty()) {
        std::unordered_set<std::uint32_t> kept;
        for (const Candidate& c : candidates) kept.insert(c.instance);
        for (Candidate& c : exact) {
            if (kept.count(c.instance) == 0) candidates.push_back(std::move(c));
        }
    }
    std::vector<scene_schema::Entity> out;
    for (const auto& c : candidates) {
        out.push_back(make_entity(info, c.box, c.members.size(), confidence_of(c.members.size(), s),
                                  "instances"));
        if (!c.subclass.empty()) out.back().extra["subclass"] = c.subclass;
        if (c.instance != 0) out.back().extra["instance_id"] = c.instance;
    }
    keep_largest(out, s.max_entities);
    return out;
}

}  // namespace

void queue_things_of_class(TaskQueue& queue, const ClassInfo& info,
                           const std::vector<Eigen::Vector3f>& pts,
                           const std::vector<std::uint32_t>& pixels, const PixelGrid& grid,
                           const ClassSettings& settings, const PendingGround& pending_ground,
                           const ExtractOptions& options, std::vector<scene_schema::Entity>& out) {
    struct Job {
        ClassSettings s;
        ClassFit fit;
        std::vector<Indices> clusters;
        std::vector<std::uint32_t> instance;             ///< per cluster: its object id, or 0
        std::vector<std::vector<Candidate>> candidates;  ///< per cluster
        std::atomic<std::size_t> left{0};                ///< clusters not fitted yet
    };
    auto job = std::make_shared<Job>();
    job->s = settings;
    job->fit = class_fit(settings);
    job->clusters =
        clusters_of_class(pts, pixels, grid, settings, job->fit.cluster, options, job->instance);
    job->candidates.resize(job->clusters.size());
    const auto finish = [&info, &pts, &pixels, &grid, &options, &out, &pending_ground](Job& j) {
        std::vector<Candidate> all;
        for (auto& c : j.candidates) {
            all.insert(all.end(), std::make_move_iterator(c.begin()),
                       std::make_move_iterator(c.end()));
        }
        if (std::any_of(all.begin(), all.end(), [](const Candidate& c) { return c.instance; })) {
            BoxFitOptions fit = own_box_fit(j.fit.box, options);
            fit.disparity_fb_px_m = grid.border.fb_px_m;
            turn_overlapping_objects(all, pts, fit, pending_ground.get());
        }
        out = things_of_class(info, std::move(all), pts, pixels, grid, j.s, options);
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
        tasks.emplace_back([job, c, finish, &pts, &pixels, &grid, &pending_ground, &options] {
            const std::optional<GroundPlane>& ground = pending_ground.get();
            Indices members = std::move(job->clusters[c]);
            job->candidates[c] =
                job->instance[c] != 0
                    ? candidates_of_instance(pts, pixels, grid, std::move(members), c,
                                             job->instance[c], job->s, job->fit, ground, options)
                    : candidates_of_cluster(pts, pixels, grid, std::move(members), c, job->s,
                                            job->fit, ground, options);
            if (--job->left == 0) finish(*job);
        });
    }
    queue.push_front(std::move(tasks));
}

}  // namespace cloud_analysis::instances
