#pragma once

/// Odometry against ground-truth poses, as the KITTI odometry benchmark scores it (Geiger,
/// Lenz, Urtasun, CVPR 2012; devkit evaluate_odometry.cpp): for every start frame and segment
/// length, the relative pose error between the estimated and true motion over the segment,
/// translation as a share of the length and rotation per metre; plus the end point's error.

#include <vector>

#include <nlohmann/json.hpp>

#include "cloud_analysis/odometry/visual_odometry.hpp"

namespace cloud_analysis {

/// The errors of one segment length.
struct SegmentErrors {
    double length_m = 0.0;
    std::size_t segments = 0;         ///< start frames with a segment this long
    double translation_pct = 0.0;     ///< mean translation error, % of the length
    double rotation_deg_per_m = 0.0;  ///< mean rotation error, degrees per metre
};

/// The errors of a drive.
struct OdometryErrors {
    std::size_t frames = 0;
    double path_m = 0.0;                 ///< length of the true path
    std::vector<SegmentErrors> lengths;  ///< the lengths the drive has
    double translation_pct = 0.0;        ///< mean over every segment of every length
    double rotation_deg_per_m = 0.0;     ///< likewise
    double end_point_m = 0.0;            ///< distance of the last estimated position from the true
    double end_point_pct = 0.0;          ///< that, % of the path
    nlohmann::json to_json() const;
};

/// The segment lengths scored for a path of `path_m` metres: KITTI's 100, 200, ... 800 m and,
/// for shorter drives, 5, 10, 20 and 50 m, those no longer than the path.
std::vector<double> segment_lengths(double path_m);

/// Scores `estimate` against `truth` (T_world_camera per frame, both with their own world).
/// Every frame is a start frame (KITTI's devkit takes every tenth). Throws
/// std::invalid_argument when the counts differ or there are fewer than two frames.
OdometryErrors evaluate_odometry(const std::vector<odometry::Pose>& estimate,
                                 const std::vector<odometry::Pose>& truth);

}  // namespace cloud_analysis
