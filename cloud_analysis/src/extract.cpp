#include "cloud_analysis/extract.hpp"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <stdexcept>
#include <unordered_map>

#include "cloud_analysis/boxes.hpp"
#include "cloud_analysis/cluster.hpp"

namespace cloud_analysis {
namespace {

/// Points of one class (camera frame) and their original cloud indices.
struct ClassPoints {
    std::vector<Eigen::Vector3f> xyz;
};

/// Voxel centroids and the member points of each voxel (indices into the input).
struct Voxels {
    std::vector<Eigen::Vector3f> centroid;
    std::vector<std::vector<std::size_t>> members;
};

Voxels voxelize(const std::vector<Eigen::Vector3f>& pts, double voxel_m) {
    Voxels v;
    if (voxel_m <= 0.0) {
        v.centroid = pts;
        v.members.resize(pts.size());
        for (std::size_t i = 0; i < pts.size(); ++i) v.members[i].push_back(i);
        return v;
    }
    std::unordered_map<std::uint64_t, std::size_t> index;
    const auto cell = [voxel_m](float c) {
        return static_cast<std::uint64_t>(
                   static_cast<std::int64_t>(std::floor(double{c} / voxel_m)) + (1 << 20)) &
               0x1FFFFF;
    };
    std::vector<Eigen::Vector3d> sums;
    for (std::size_t i = 0; i < pts.size(); ++i) {
        const std::uint64_t key =
            (cell(pts[i].x()) << 42) | (cell(pts[i].y()) << 21) | cell(pts[i].z());
        auto [it, inserted] = index.emplace(key, sums.size());
        if (inserted) {
            sums.emplace_back(Eigen::Vector3d::Zero());
            v.members.emplace_back();
        }
        sums[it->second] += pts[i].cast<double>();
        v.members[it->second].push_back(i);
    }
    v.centroid.reserve(sums.size());
    for (std::size_t k = 0; k < sums.size(); ++k) {
        v.centroid.push_back((sums[k] / static_cast<double>(v.members[k].size())).cast<float>());
    }
    return v;
}

/// Drops stereo smear behind a thing: per viewing direction (0.5 degree azimuth bins), points
/// farther (bird's-eye range) than the nearest one plus the prior's diagonal plus a margin;
/// and points implausibly high above or below the ground.
std::vector<Eigen::Vector3f> drop_outliers(const std::vector<Eigen::Vector3f>& pts,
                                           const ClassSettings& s,
                                           const std::optional<GroundPlane>& ground,
                                           double margin_m) {
    if (!s.has_prior() || pts.size() < 10) return pts;
    constexpr double kBinRad = 0.5 * 3.14159265358979323846 / 180.0;
    std::vector<double> range(pts.size());
    std::vector<long> bin(pts.size());
    std::unordered_map<long, double> nearest;
    for (std::size_t i = 0; i < pts.size(); ++i) {
        const double x = pts[i].x(), z = pts[i].z();
        range[i] = std::hypot(x, z);
        bin[i] = std::lround(std::atan2(x, z) / kBinRad);
        auto [it, inserted] = nearest.emplace(bin[i], range[i]);
        if (!inserted) it->second = std::min(it->second, range[i]);
    }
    const double depth = std::hypot(s.prior_L_m, s.prior_W_m) + margin_m;
    std::vector<Eigen::Vector3f> kept;
    kept.reserve(pts.size());
    for (std::size_t i = 0; i < pts.size(); ++i) {
        if (range[i] > nearest[bin[i]] + depth) continue;
        if (ground) {
            const double h = ground->height(pts[i].cast<double>());
            if (h < -0.5 || h > 1.5 * s.prior_H_m + 0.5) continue;
        }
        kept.push_back(pts[i]);
    }
    return kept.size() >= static_cast<std::size_t>(s.min_points) ? kept : pts;
}

/// Splits a thing whose box is much longer than its prior into pieces of about the prior
/// length, cutting at the emptiest place near each even cut (touching parked cars).
std::vector<std::vector<Eigen::Vector3f>> split_long(const std::vector<Eigen::Vector3f>& pts,
                                                     const OrientedBox& box,
                                                     const ClassSettings& s) {
    if (!s.has_prior() || box.L_m <= s.split_factor * s.prior_L_m) return {pts};
    const int pieces = std::max(2, static_cast<int>(std::lround(box.L_m / s.prior_L_m)));
    const double c = std::cos(box.theta), sn = std::sin(box.theta);
    std::vector<double> along(pts.size());
    double lo = 1e300, hi = -1e300;
    for (std::size_t i = 0; i < pts.size(); ++i) {
        along[i] = double{pts[i].x()} * c - double{pts[i].z()} * sn;
        lo = std::min(lo, along[i]);
        hi = std::max(hi, along[i]);
    }
    // Density histogram along the heading, 0.1 m bins.
    const double bin = 0.1;
    const int bins = std::max(1, static_cast<int>(std::ceil((hi - lo) / bin)) + 1);
    std::vector<int> hist(static_cast<std::size_t>(bins), 0);
    for (double a : along) ++hist[static_cast<std::size_t>((a - lo) / bin)];
    std::vector<double> cuts;
    const double piece = (hi - lo) / pieces;
    for (int k = 1; k < pieces; ++k) {
        const double even = lo + k * piece;
        const int centre = static_cast<int>((even - lo) / bin);
        const int reach = static_cast<int>(0.25 * s.prior_L_m / bin);
        int best = centre;
        for (int b = std::max(0, centre - reach); b <= std::min(bins - 1, centre + reach); ++b) {
            if (hist[static_cast<std::size_t>(b)] < hist[static_cast<std::size_t>(best)]) best = b;
        }
        cuts.push_back(lo + (best + 0.5) * bin);
    }
    std::sort(cuts.begin(), cuts.end());
    std::vector<std::vector<Eigen::Vector3f>> parts(cuts.size() + 1);
    for (std::size_t i = 0; i < pts.size(); ++i) {
        const auto k = static_cast<std::size_t>(
            std::upper_bound(cuts.begin(), cuts.end(), along[i]) - cuts.begin());
        parts[k].push_back(pts[i]);
    }
    return parts;
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

/// Drops "shadow" clusters: clusters of a thing class whose pixels mostly lie among the pixels
/// of a nearer cluster of the same class (within `radius_px`). A real object behind another is
/// occluded there and shows only beside it; interleaved pixels are wrong matches on the nearer
/// object (dark, textureless car bodies) reprojected too far.
std::vector<std::vector<std::size_t>> drop_shadow_clusters(
    std::vector<std::vector<std::size_t>> clusters, const std::vector<Eigen::Vector3f>& pts,
    const std::vector<std::uint32_t>& pixels, const PixelGrid& grid, double min_gap_m,
    double max_shared_fraction, int radius_px) {
    if (!grid.valid() || clusters.size() < 2) return clusters;
    std::vector<double> mean_range(clusters.size(), 0.0);
    for (std::size_t c = 0; c < clusters.size(); ++c) {
        for (std::size_t i : clusters[c])
            mean_range[c] += std::hypot(double{pts[i].x()}, double{pts[i].z()});
        mean_range[c] /= static_cast<double>(clusters[c].size());
    }
    std::vector<int> owner(static_cast<std::size_t>(grid.width_px) * grid.height_px, -1);
    for (std::size_t c = 0; c < clusters.size(); ++c) {
        for (std::size_t i : clusters[c]) owner[pixels[i]] = static_cast<int>(c);
    }
    std::vector<char> keep(clusters.size(), 1);
    for (std::size_t c = 0; c < clusters.size(); ++c) {
        std::size_t shared = 0;
        for (std::size_t i : clusters[c]) {
            const int u0 = static_cast<int>(pixels[i] % grid.width_px);
            const int v0 = static_cast<int>(pixels[i] / grid.width_px);
            bool found = false;
            for (int dv = -radius_px; dv <= radius_px && !found; ++dv) {
                for (int du = -radius_px; du <= radius_px && !found; ++du) {
                    const int u = u0 + du, v = v0 + dv;
                    if (u < 0 || v < 0 || u >= grid.width_px || v >= grid.height_px) continue;
                    const int o = owner[static_cast<std::size_t>(v) * grid.width_px + u];
                    found = o >= 0 &&
                            mean_range[static_cast<std::size_t>(o)] + min_gap_m < mean_range[c];
                }
            }
            if (found) ++shared;
        }
        if (static_cast<double>(shared) >
            max_shared_fraction * static_cast<double>(clusters[c].size())) {
            keep[c] = 0;
        }
    }
    std::vector<std::vector<std::size_t>> kept;
    for (std::size_t c = 0; c < clusters.size(); ++c) {
        if (keep[c]) kept.push_back(std::move(clusters[c]));
    }
    return kept;
}

std::vector<scene_schema::Entity> instances_of_class(const ClassInfo& info,
                                                     const std::vector<Eigen::Vector3f>& pts,
                                                     const std::vector<std::uint32_t>& pixels,
                                                     const PixelGrid& grid, const ClassSettings& s,
                                                     const std::optional<GroundPlane>& ground,
                                                     const ExtractOptions& options) {
    std::vector<scene_schema::Entity> out;
    const Voxels voxels = voxelize(pts, s.voxel_m);
    ClusterOptions co;
    co.distance_at_10m_m = s.cluster_distance_m;
    co.growth = s.cluster_growth;
    co.distance_max_m = s.cluster_distance_max_m;
    co.min_points = 1;
    std::vector<std::vector<std::size_t>> clusters;
    for (const auto& cluster : euclidean_clusters(voxels.centroid, co)) {
        std::vector<std::size_t> members;
        for (std::size_t v : cluster) {
            members.insert(members.end(), voxels.members[v].begin(), voxels.members[v].end());
        }
        if (members.size() >= static_cast<std::size_t>(s.min_points)) clusters.push_back(members);
    }
    if (s.thing && s.has_prior()) {
        clusters = drop_shadow_clusters(std::move(clusters), pts, pixels, grid,
                                        std::hypot(s.prior_L_m, s.prior_W_m),
                                        options.shadow_fraction, options.shadow_radius_px);
    }

    BoxFitOptions fit;
    if (s.thing && s.has_prior()) {
        fit.prior_L_m = s.prior_L_m;
        fit.prior_W_m = s.prior_W_m;
        fit.prior_H_m = s.prior_H_m;
    }
    fit.rest_on_ground = s.thing;
    for (const auto& cluster : clusters) {
        std::vector<Eigen::Vector3f> members;
        members.reserve(cluster.size());
        for (std::size_t i : cluster) members.push_back(pts[i]);
        if (s.thing) members = drop_outliers(members, s, ground, options.outlier_margin_m);
        const OrientedBox first = fit_upright_box(members, ground, fit);
        for (const auto& part : split_long(members, first, s)) {
            if (part.size() < static_cast<std::size_t>(s.min_points)) continue;
            const OrientedBox box =
                part.size() == members.size() ? first : fit_upright_box(part, ground, fit);
            // A thing whose points all lie near the ground is mislabelled road, not an object.
            if (s.thing && s.prior_H_m > 0.0 && ground &&
                box.H_m < options.min_height_fraction * s.prior_H_m) {
                continue;
            }
            out.push_back(
                make_entity(info, box, part.size(), confidence_of(part.size(), s), "instances"));
        }
    }
    std::stable_sort(out.begin(), out.end(),
                     [](const auto& a, const auto& b) { return a.point_count > b.point_count; });
    if (out.size() > static_cast<std::size_t>(s.max_entities)) {
        out.resize(static_cast<std::size_t>(s.max_entities));
    }
    return out;
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
    if (!(outlier_margin_m >= 0.0)) throw std::invalid_argument("outlier_margin_m: must be >= 0");
    if (!(shadow_fraction > 0.0 && shadow_fraction <= 1.0)) {
        throw std::invalid_argument("shadow_fraction: must be in (0, 1]");
    }
    if (shadow_radius_px < 0) throw std::invalid_argument("shadow_radius_px: must be >= 0");
    if (!(min_height_fraction >= 0.0 && min_height_fraction < 1.0)) {
        throw std::invalid_argument("min_height_fraction: must be in [0, 1)");
    }
}

scene_schema::EntityDocument extract_entities(const LabeledCloud& cloud, const Palette& palette,
                                              const StereoCamera& camera,
                                              const ExtractOptions& options) {
    (void)camera;
    options.validate();
    if (cloud.class_index.size() != cloud.xyz_m.size()) {
        throw std::invalid_argument("cloud: class_index and xyz_m differ in size");
    }
    // Points per palette class, within range.
    std::vector<std::vector<Eigen::Vector3f>> per_class(palette.classes.size());
    std::vector<std::vector<std::uint32_t>> per_class_pixels(palette.classes.size());
    PixelGrid grid;
    if (cloud.pixel.size() == cloud.size() && cloud.width_px > 0 && cloud.height_px > 0) {
        grid = PixelGrid{cloud.width_px, cloud.height_px};
        for (std::uint32_t px : cloud.pixel) {
            if (px >= static_cast<std::uint64_t>(grid.width_px) * grid.height_px)
                grid = PixelGrid{};
        }
    }
    for (std::size_t i = 0; i < cloud.size(); ++i) {
        const auto k = cloud.class_index[i];
        const auto& p = cloud.xyz_m[i];
        if (k == kVoidClass || k >= palette.classes.size()) continue;
        if (!(p.z() > 0.0f && double{p.z()} < options.max_range_m) || !p.allFinite()) continue;
        per_class[k].push_back(p);
        per_class_pixels[k].push_back(grid.valid() ? cloud.pixel[i] : 0);
    }

    scene_schema::EntityDocument doc;
    std::optional<GroundPlane> ground;
    if (options.method == "instances") {
        std::vector<Eigen::Vector3f> ground_pts;
        for (std::size_t k = 0; k < palette.classes.size(); ++k) {
            const auto& names = options.ground_classes;
            if (std::find(names.begin(), names.end(), palette.classes[k].name) != names.end()) {
                ground_pts.insert(ground_pts.end(), per_class[k].begin(), per_class[k].end());
            }
        }
        ground = fit_ground_plane(ground_pts, options.ground);
        if (ground) {
            doc.extra["ground_plane"] = {
                {"normal", {ground->normal.x(), ground->normal.y(), ground->normal.z()}},
                {"d", ground->d},
                {"camera_height_m", ground->camera_height_m()},
                {"inliers", ground->inliers}};
        }
    }

    for (std::size_t k = 0; k < palette.classes.size(); ++k) {
        const ClassInfo& info = palette.classes[k];
        const ClassSettings s = options.classes.find(info.name);
        const auto& pts = per_class[k];
        if (!s.entity || pts.size() < static_cast<std::size_t>(s.min_points)) continue;
        std::vector<scene_schema::Entity> made;
        if (options.method == "instances") {
            made = instances_of_class(info, pts, per_class_pixels[k], grid, s, ground, options);
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
            made.push_back(
                make_entity(info, box, pts.size(), confidence_of(pts.size(), s), options.method));
        }
        for (std::size_t n = 0; n < made.size(); ++n) {
            std::string stem = info.name;
            std::replace(stem.begin(), stem.end(), ' ', '-');
            made[n].id = stem + "-" + std::to_string(n + 1);
            doc.entities.push_back(std::move(made[n]));
        }
    }
    return doc;
}

}  // namespace cloud_analysis
