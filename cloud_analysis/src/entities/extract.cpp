#include "cloud_analysis/entities/extract.hpp"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <exception>
#include <future>
#include <stdexcept>
#include <utility>

#include "cloud_analysis/entities/boxes.hpp"
#include "cloud_analysis/entities/candidate.hpp"
#include "cloud_analysis/entities/cluster.hpp"
#include "cloud_analysis/entities/suppression.hpp"
#include "cloud_analysis/entities/things.hpp"
#include "cloud_analysis/support/task_queue.hpp"

namespace cloud_analysis {
namespace {

using namespace instances;

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

/// Moves each chunk's points of every class (written from start[c][k] to end[c][k]) right
/// after the previous chunk's, and cuts the class's points to those kept.
void close_gaps(ClassPoints& out, const std::vector<char>& keep_pixels,
                const std::vector<std::vector<std::size_t>>& start,
                const std::vector<std::vector<std::size_t>>& end) {
    auto& per_class = out.xyz_m;
    auto& per_class_pixels = out.pixel;
    const std::size_t chunks = start.size();
    for (std::size_t k = 0; k < per_class.size(); ++k) {
        std::size_t kept = end[0][k];
        for (std::size_t c = 1; c < chunks; ++c) {
            const auto from = static_cast<std::ptrdiff_t>(start[c][k]);
            const auto to = static_cast<std::ptrdiff_t>(end[c][k]);
            std::copy(per_class[k].begin() + from, per_class[k].begin() + to,
                      per_class[k].begin() + static_cast<std::ptrdiff_t>(kept));
            if (keep_pixels[k]) {
                std::copy(per_class_pixels[k].begin() + from, per_class_pixels[k].begin() + to,
                          per_class_pixels[k].begin() + static_cast<std::ptrdiff_t>(kept));
            }
            kept += end[c][k] - start[c][k];
        }
        per_class[k].resize(kept);
        if (keep_pixels[k]) per_class_pixels[k].resize(kept);
    }
}

/// Column of pixel p, for pixels mostly in increasing order: the row's first pixel is
/// found by a division only when p leaves the row.
inline std::uint32_t column_of(std::uint32_t p, std::uint32_t width, std::uint32_t& row_start) {
    if (p - row_start >= width) row_start = p / width * width;
    return p - row_start;
}

/// What the first pass of points_by_class finds in each chunk of the cloud.
struct ChunkScan {
    /// Per chunk and class: its points (an upper bound once the columns are thinned), then the
    /// slot its first one is written to.
    std::vector<std::vector<std::size_t>> start;
    std::vector<std::uint32_t> last_pixel;  ///< per chunk: its largest pixel
    std::vector<std::uint32_t> first_col;   ///< per chunk: its leftmost column
    std::vector<std::uint32_t> last_col;    ///< per chunk: its rightmost column
};

/// The first pass of points_by_class over the cloud's `chunks` chunks (in parallel): each
/// chunk's points of every class and its pixels' extent (when has_pixels).
ChunkScan scan_chunks(const LabeledCloud& cloud, std::size_t classes, std::size_t chunks,
                      bool has_pixels, std::uint32_t width) {
    ChunkScan scan;
    auto& start = scan.start;
    auto& last_pixel = scan.last_pixel;
    auto& first_col = scan.first_col;
    auto& last_col = scan.last_col;
    start.assign(chunks, std::vector<std::size_t>(classes, 0));
    last_pixel.assign(chunks, 0);
    first_col.assign(chunks, std::numeric_limits<std::uint32_t>::max());
    last_col.assign(chunks, 0);
    for_each_chunk(cloud.size(), chunks, [&](std::size_t c, std::size_t first, std::size_t last) {
        // Every point of each class (an upper bound once the columns are thinned).
        auto& size = start[c];
        for (std::size_t i = first; i < last; ++i) {
            const auto k = cloud.class_index[i];
            if (k < classes) ++size[k];
        }
        std::uint32_t row_start = 0;
        for (std::size_t i = first; has_pixels && i < last; ++i) {
            last_pixel[c] = std::max(last_pixel[c], cloud.pixel[i]);
            const std::uint32_t u = column_of(cloud.pixel[i], width, row_start);
            first_col[c] = std::min(first_col[c], u);
            last_col[c] = std::max(last_col[c], u);
        }
    });
    return scan;
}

/// Gives `out` the cloud's pixel grid (size, the columns holding points, depth edges and
/// instances) when every pixel lies on it; whether it does.
bool take_grid(ClassPoints& out, const LabeledCloud& cloud, const ChunkScan& scan, bool has_pixels,
               std::uint32_t width) {
    const auto& last_pixel = scan.last_pixel;
    const bool grid = has_pixels && cloud.width_px > 0 && cloud.height_px > 0 &&
                      *std::max_element(last_pixel.begin(), last_pixel.end()) <
                          static_cast<std::uint64_t>(cloud.width_px) * cloud.height_px;
    if (grid) {
        out.width_px = cloud.width_px;
        out.height_px = cloud.height_px;
        out.first_column = static_cast<int>(
            std::min(*std::min_element(scan.first_col.begin(), scan.first_col.end()), width - 1));
        out.last_column =
            static_cast<int>(*std::max_element(scan.last_col.begin(), scan.last_col.end()));
        out.depth_edge = cloud.depth_edge;
        out.instance_id = cloud.instance_id;
        out.depth_m = cloud.depth_m;
    }
    return grid;
}

/// Sizes each class's points (and its pixels, when kept) for every point of the class, and
/// turns start[c][k] from chunk c's points of class k into the slot of the first one.
void size_classes(ClassPoints& out, const std::vector<char>& keep_pixels,
                  std::vector<std::vector<std::size_t>>& start) {
    const std::size_t chunks = start.size();
    // Sized for every point of the class, written by index, then cut to the points kept.
    for (std::size_t k = 0; k < out.xyz_m.size(); ++k) {
        std::size_t total = 0;
        for (std::size_t c = 0; c < chunks; ++c) total += std::exchange(start[c][k], total);
        out.xyz_m[k].resize(total);
        if (keep_pixels[k]) out.pixel[k].resize(total);
    }
}

/// The second pass of points_by_class over the cloud's chunks (in parallel): each chunk writes
/// its points of every class kept (columns by column_mask, the pixels of classes whose pixels
/// are kept by `lattice`, depths by the selection) from slot
/// end[c][k] on, and leaves end[c][k] past its last one.
void write_points(ClassPoints& out, const LabeledCloud& cloud, const ClassSelection& selection,
                  const std::vector<std::uint32_t>& column_mask, std::uint32_t lattice,
                  std::uint32_t width, bool grid, std::vector<std::vector<std::size_t>>& end) {
    const std::size_t classes = column_mask.size();
    auto& per_class = out.xyz_m;
    auto& per_class_pixels = out.pixel;
    const auto taken = [&](std::size_t i, std::uint16_t k, std::uint32_t& row_start) {
        const bool on_lattice = lattice != 0 && selection.keep_pixels[k];
        if (column_mask[k] == 0 && !on_lattice) return true;  // no pixel needed
        const std::uint32_t u = column_of(cloud.pixel[i], width, row_start);
        return pixel_taken(column_mask[k], on_lattice, lattice, u, row_start / width);
    };
    const double max_depth = selection.max_depth_m;
    const std::size_t chunks = end.size();
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
}

/// The entity of a class by one of the thesis's one-per-class extractors ("centroid",
/// "average", "variance"); each of `pts` stands for `step` points of the cloud.
scene_schema::Entity thesis_entity(const ClassInfo& info, const std::vector<Eigen::Vector3f>& pts,
                                   std::size_t step, const ClassSettings& s,
                                   const std::string& method) {
    OrientedBox box;
    if (method == "centroid") {
        const Eigen::Vector3d size = s.has_prior()
                                         ? Eigen::Vector3d(s.prior_L_m, s.prior_H_m, s.prior_W_m)
                                         : Eigen::Vector3d(1.0, 1.0, 1.0);
        box = centroid_box(pts, size);
    } else if (method == "average") {
        box = average_box(pts);
    } else {
        box = variance_box(pts);
    }
    const std::size_t n = pts.size() * step;
    return make_entity(info, box, n, confidence_of(n, s), method);
}

/// Per palette class, whether it is a thing; throws std::invalid_argument when `points` does
/// not hold one entry per class or a thing class has no pixels.
std::vector<char> thing_flags(const ClassPoints& points, const Palette& palette,
                              const ExtractOptions& options) {
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
    return is_thing;
}

/// Drops the stuff entities (of classes not flagged in is_thing) with more than `fraction` of
/// their footprint inside the thing entities' footprints.
void drop_stuff_on_things(std::vector<std::vector<scene_schema::Entity>>& made,
                          const std::vector<char>& is_thing, double fraction) {
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
                                      return footprint_share_inside(e, footprints) > fraction;
                                  }),
                   list.end());
    }
}

/// The document of the entities made per class: ids "<class>-<n>" (spaces as dashes) in
/// class order, the ground plane in extra["ground_plane"] when there is one.
scene_schema::EntityDocument document_of(std::vector<std::vector<scene_schema::Entity>>& made,
                                         const Palette& palette,
                                         const std::optional<GroundPlane>& ground) {
    scene_schema::EntityDocument doc;
    if (ground) {
        doc.extra["ground_plane"] = {
            {"normal", {ground->normal.x(), ground->normal.y(), ground->normal.z()}},
            {"d", ground->d},
            {"camera_height_m", ground->camera_height_m()},
            {"inliers", ground->inliers}};
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

}  // namespace

void ExtractOptions::validate() const {
    const auto fail_if = [](bool bad, const char* message) {
        if (bad) throw std::invalid_argument(message);
    };
    if (method != "instances" && method != "centroid" && method != "average" &&
        method != "variance") {
        throw std::invalid_argument(
            "method: must be instances, centroid, average or variance (got '" + method + "')");
    }
    classes.validate();
    ground.validate();
    fail_if(!(max_range_m > 0.0), "max_range_m: must be > 0");
    if (clustering != "euclidean" && clustering != "image") {
        throw std::invalid_argument("clustering: must be euclidean or image (got '" + clustering +
                                    "')");
    }
    fail_if(image_radius_px < 1, "image_radius_px: must be >= 1");
    fail_if(!(outlier_margin_m >= 0.0), "outlier_margin_m: must be >= 0");
    fail_if(!(shadow_fraction > 0.0 && shadow_fraction <= 1.0),
            "shadow_fraction: must be in (0, 1]");
    fail_if(shadow_radius_px < 0, "shadow_radius_px: must be >= 0");
    fail_if(!(near_trim_fraction >= 0.0 && near_trim_fraction < 0.2),
            "near_trim_fraction: must be in [0, 0.2)");
    fail_if(!(van_min_height_m > 0.0 && van_min_height_m < 100.0),
            "van_min_height_m: must be in (0, 100) metres");
    if (!(van_prior_L_m > 0.0 && van_prior_L_m < 100.0 && van_prior_W_m > 0.0 &&
          van_prior_W_m < 100.0)) {
        throw std::invalid_argument("van_prior_L_m, van_prior_W_m: must be in (0, 100) metres");
    }
    fail_if(!(van_max_L_m >= van_prior_L_m && van_max_L_m < 100.0),
            "van_max_L_m: must be in [van_prior_L_m, 100) metres");
    if (!(far_column_length_fraction == 0.0 ||
          (far_column_length_fraction >= 1.0 && far_column_length_fraction <= 3.0))) {
        throw std::invalid_argument("far_column_length_fraction: must be 0 or in [1, 3]");
    }
    fail_if(!(min_width_px >= 0.0 && min_width_px < 1e6), "min_width_px: must be >= 0");
    fail_if(!(strip_beside_width_px >= 0.0 && strip_beside_width_px < 1e6),
            "strip_beside_width_px: must be >= 0");
    fail_if(!(strip_beside_gap_m >= 0.0 && strip_beside_gap_m < 1e6),
            "strip_beside_gap_m: must be >= 0");
    fail_if(!(fragment_height_fraction >= 0.0 && fragment_height_fraction <= 1.0),
            "fragment_height_fraction: must be in [0, 1]");
    fail_if(row_model != "rules" && row_model != "partition",
            "row_model: must be rules or partition");
    fail_if(!(min_height_fraction >= 0.0 && min_height_fraction < 1.0),
            "min_height_fraction: must be in [0, 1)");
    fail_if(!(min_face_share >= 0.0 && min_face_share < 1.0), "min_face_share: must be in [0, 1)");
    fail_if(!(family_min_height_m >= 0.0 && family_min_height_m < 1e3),
            "family_min_height_m: must be >= 0");
    fail_if(!(fx_px >= 0.0 && fy_px >= 0.0 && fx_px < 1e7 && fy_px < 1e7),
            "fx_px, fy_px: must be >= 0");
    fail_if(!(row_low_fraction >= 0.0 && row_low_fraction < 1.0),
            "row_low_fraction: must be in [0, 1)");
    fail_if(!(row_low_extent_m > 0.0), "row_low_extent_m: must be > 0");
    fail_if(!(row_gap_m >= 0.0), "row_gap_m: must be >= 0");
    fail_if(!(row_valley_depth_m >= 0.0 && row_valley_depth_m < 100.0),
            "row_valley_depth_m: must be in [0, 100) metres");
    fail_if(!(row_valley_min_length_fraction > 0.0 && row_valley_min_length_fraction < 100.0),
            "row_valley_min_length_fraction: must be in (0, 100)");
    fail_if(!(row_valley_min_peak_fraction >= 0.0 && row_valley_min_peak_fraction <= 2.0),
            "row_valley_min_peak_fraction: must be in [0, 2]");
    fail_if(!(row_valley_min_piece_m > 0.0 && row_valley_min_piece_m < 100.0),
            "row_valley_min_piece_m: must be in (0, 100) metres");
    fail_if(!(row_valley_bin_m >= 0.01 && row_valley_bin_m <= 10.0),
            "row_valley_bin_m: must be in [0.01, 10] metres");
    fail_if(!(row_valley_closing_m >= 0.0 && row_valley_closing_m <= 10.0),
            "row_valley_closing_m: must be in [0, 10] metres");
    fail_if(threads < 1, "threads: must be >= 1");
    fail_if(point_lattice_px != 1 && point_lattice_px != 2 && point_lattice_px != 4 &&
                point_lattice_px != 8,
            "point_lattice_px: must be 1, 2, 4 or 8");
    fail_if(!(stuff_on_thing_fraction > 0.0 && stuff_on_thing_fraction <= 1.0),
            "stuff_on_thing_fraction: must be in (0, 1]");
}

double min_seen_area_m2(const ClassSettings& s, const ExtractOptions& options) {
    if (!s.has_prior() || !(options.min_face_share > 0.0) || !(options.fx_px > 0.0) ||
        !(options.fy_px > 0.0)) {
        return 0.0;
    }
    return options.min_face_share * s.prior_W_m * s.prior_H_m;
}

double thing_seen_area_m2(const std::vector<Eigen::Vector3f>& pts,
                          const std::vector<std::size_t>& members, const ExtractOptions& options) {
    const double cell = options.point_lattice_px;
    return instances::seen_area_m2(pts, members, options.fx_px / cell, options.fy_px / cell);
}

ClassSelection class_selection(const Palette& palette, const ExtractOptions& options) {
    ClassSelection selection;
    selection.max_depth_m = options.max_range_m;
    for (const ClassInfo& info : palette.classes) {
        const ClassSettings s = options.classes.find(info.name);
        selection.column_mask.push_back(static_cast<std::uint32_t>(s.column_step) - 1);
        selection.keep_pixels.push_back(s.thing ? 1 : 0);
    }
    selection.lattice_mask = static_cast<std::uint32_t>(options.point_lattice_px) - 1;
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
    out.border = cloud.border;
    out.xyz_m.resize(classes);
    out.pixel.resize(classes);
    // Split on `chunks` threads over contiguous point ranges (each chunk writes its points of a
    // class after the previous chunks' ones, so the order is the points' order): count, size,
    // write, then close the gaps the range check left.
    const std::size_t chunks = std::clamp<std::size_t>(
        cloud.size() / kMinChunkPoints, 1, static_cast<std::size_t>(std::max(threads, 1)));
    const bool has_pixels = cloud.pixel.size() == cloud.size();
    // Columns are thinned only when the cloud knows its pixels.
    std::vector<std::uint32_t> column_mask(classes, 0);
    std::uint32_t lattice = 0;
    if (has_pixels && cloud.width_px > 0) {
        column_mask = selection.column_mask;
        lattice = selection.lattice_mask;
    }
    out.weight.resize(classes);
    for (std::size_t k = 0; k < classes; ++k) out.weight[k] = std::size_t{column_mask[k]} + 1;
    const auto width = static_cast<std::uint32_t>(std::max(cloud.width_px, 1));
    ChunkScan scan = scan_chunks(cloud, classes, chunks, has_pixels, width);
    const bool grid = take_grid(out, cloud, scan, has_pixels, width);
    size_classes(out, selection.keep_pixels, scan.start);
    std::vector<std::vector<std::size_t>> end = scan.start;
    write_points(out, cloud, selection, column_mask, lattice, width, grid, end);
    close_gaps(out, selection.keep_pixels, scan.start, end);
    return out;
}

scene_schema::EntityDocument extract_entities(const LabeledCloud& cloud, const Palette& palette,
                                              const StereoCamera& camera,
                                              const ExtractOptions& options) {
    options.validate();
    ClassPoints points = points_by_class(cloud, class_selection(palette, options), options.threads);
    if (!(points.border.fb_px_m > 0.0) && camera.fx_px > 0.0 && camera.baseline_m > 0.0) {
        points.border = match_border(camera);
    }
    return extract_entities(points, palette, options);
}

scene_schema::EntityDocument extract_entities(const ClassPoints& points, const Palette& palette,
                                              const ExtractOptions& options) {
    options.validate();
    const std::vector<char> is_thing = thing_flags(points, palette, options);
    const auto& per_class = points.xyz_m;
    const auto& per_class_pixels = points.pixel;
    const auto& step = points.weight;
    PixelGrid grid{points.width_px, points.height_px, points.first_column, points.last_column,
                   points.border};
    if (grid.valid() && points.depth_edge.size() == static_cast<std::size_t>(grid.width_px) *
                                                        static_cast<std::size_t>(grid.height_px)) {
        grid.depth_edge = &points.depth_edge;
    }
    if (grid.valid() && points.instance_id.size() == static_cast<std::size_t>(grid.width_px) *
                                                         static_cast<std::size_t>(grid.height_px)) {
        grid.instance_id = &points.instance_id;
        if (points.depth_m.size() == points.instance_id.size()) grid.depth_m = &points.depth_m;
    }

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
                made[k].push_back(thesis_entity(info, pts, step[k], s, options.method));
            }
        });
    }
    queue.run(options.threads);
    if (options.method == "instances" && options.stuff_on_thing_fraction < 1.0) {
        drop_stuff_on_things(made, is_thing, options.stuff_on_thing_fraction);
    }
    return document_of(made, palette, pending_ground.get());
}

}  // namespace cloud_analysis
