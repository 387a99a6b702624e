#pragma once

/// Ground plane estimation by RANSAC on road/sidewalk points (Fischler & Bolles 1981), refined
/// by least squares on the inliers.

#include <cstdint>
#include <optional>
#include <vector>

#include <Eigen/Core>

namespace cloud_analysis {

/// Plane n . p + d = 0 in the camera frame, n unit length and pointing up (n.y < 0).
struct GroundPlane {
    Eigen::Vector3d normal{0.0, -1.0, 0.0};  ///< unit normal pointing up (towards -y)
    double d = 1.65;                         ///< offset, metres: camera height above the plane
    std::size_t inliers = 0;                 ///< supporting points
    /// Signed height of p above the plane, metres (positive above).
    double height(const Eigen::Vector3d& p) const { return normal.dot(p) + d; }
    /// Height of the camera centre above the plane, metres.
    double camera_height_m() const { return d; }
};

/// RANSAC settings of fit_ground_plane.
struct GroundOptions {
    double inlier_distance_m = 0.10;  ///< max point-to-plane distance of an inlier, metres
    int iterations = 300;             ///< RANSAC hypotheses, >= 1
    double max_tilt_deg = 20.0;       ///< max angle between the normal and -y, degrees
    double max_range_m = 40.0;        ///< only points nearer than this (z) vote, metres
    std::size_t min_inliers = 200;    ///< fewer inliers means no plane
    std::size_t max_samples = 20000;  ///< points used (evenly subsampled), >= 3
    std::uint32_t seed = 1;           ///< random seed (deterministic results)
    /// Throws std::invalid_argument naming the bad field.
    void validate() const;
};

/// Fits the ground plane; nullopt when too few points agree.
std::optional<GroundPlane> fit_ground_plane(const std::vector<Eigen::Vector3f>& points_m,
                                            const GroundOptions& options);

}  // namespace cloud_analysis
