#pragma once

/// Parts of the "instances" extractor shared by its files (see extract.hpp for the stage):
/// thing candidates before they become entities, the pixel grid they are reasoned on in image
/// space, and the per-class settings of clustering and box fitting.

#include <cstddef>
#include <future>
#include <optional>
#include <string>
#include <vector>

#include <scene_schema/entities.hpp>

#include "cloud_analysis/cloud/types.hpp"
#include "cloud_analysis/entities/boxes.hpp"
#include "cloud_analysis/entities/class_config.hpp"
#include "cloud_analysis/entities/cluster.hpp"
#include "cloud_analysis/entities/ground.hpp"

namespace cloud_analysis::instances {

/// Point indices into one class's points.
using Indices = std::vector<std::size_t>;

/// The ground plane, fitted on one thread while the classes are clustered on the others.
using PendingGround = std::shared_future<std::optional<GroundPlane>>;

/// Pixel grid of the source image, to reason about clusters in image space.
struct PixelGrid {
    int width_px = 0;      ///< columns; 0 when the pixels are unknown
    int height_px = 0;     ///< rows; 0 when the pixels are unknown
    int first_column = 0;  ///< leftmost column holding a point (the edge of what stereo sees)
    int last_column = 0;   ///< rightmost column holding a point
    MatchBorder border;    ///< the matcher's left border at each depth
    /// Per pixel, 1 on the far side of a depth step (ClassPoints::depth_edge); null when unknown
    /// or not used.
    const std::vector<std::uint8_t>* depth_edge = nullptr;
    /// Per pixel, the object of an instance image (ClassPoints::instance_id, 0 = none); null
    /// without one.
    const std::vector<std::uint32_t>* instance_id = nullptr;
    /// Per pixel, the depth of its point, metres (0 = none; ClassPoints::depth_m); null
    /// without an instance image.
    const std::vector<float>* depth_m = nullptr;
    bool valid() const { return width_px > 0 && height_px > 0; }
};

/// One thing instance before it becomes an entity.
struct Candidate {
    OrientedBox box;             ///< fitted box
    Indices members;             ///< the points of the class it holds
    double range_m = 0.0;        ///< mean bird's-eye range of the points
    std::size_t group = 0;       ///< pieces cut from one 3D cluster at clear gaps share a group
    bool fragment = false;       ///< short (a strip) or sparse (under min_points): edge smear?
    std::string subclass;        ///< size family ("car", "van") of ExtractOptions::family_class
    std::uint32_t instance = 0;  ///< the object of the instance image it is (0: clustered)
};

/// Clustering and box-fit settings of a class.
struct ClassFit {
    ClusterOptions cluster;  ///< distances from the class's settings, min_points 1
    BoxFitOptions box;       ///< the class's prior (things), resting on the ground (things)
};

/// The clustering and box-fit settings of class settings `s`.
ClassFit class_fit(const ClassSettings& s);

/// The entity of a fitted box (sizes at least 1 mm, confidence clamped to [0, 1]); no id.
scene_schema::Entity make_entity(const ClassInfo& info, const OrientedBox& box,
                                 std::size_t point_count, double confidence,
                                 const std::string& method);

/// Square metres of surface the points `members` cover, each (z / fx) (z / fy) at its own depth.
double seen_area_m2(const std::vector<Eigen::Vector3f>& pts, const Indices& members, double fx_px,
                    double fy_px);

/// confidence = n / (n + 2 * min_points): 1/3 at the minimum, -> 1 with many points.
double confidence_of(std::size_t n, const ClassSettings& s);

/// The members within the window of bird's-eye range `extent_m` long that holds most of them:
/// the pixels of one object mostly show its surface, which spans at most its diagonal in range;
/// the rest took a nearer or farther surface's disparity (the matching window straddling the
/// object's outline, a mask drawn past it). All of them when fewer than `min_points` remain.
Indices densest_range_window(const std::vector<Eigen::Vector3f>& pts, const Indices& members,
                             double extent_m, std::size_t min_points);

/// Keeps the `max_entities` entities with the most points, largest first (stable).
void keep_largest(std::vector<scene_schema::Entity>& entities, int max_entities);

}  // namespace cloud_analysis::instances
