#pragma once

/// Metric reprojection of a disparity map with the Q matrix of the rig, and semantic
/// association of each point with the class of its pixel.

#include "cloud_analysis/io.hpp"
#include "cloud_analysis/semantic.hpp"
#include "cloud_analysis/types.hpp"

namespace cloud_analysis {

/// Which reprojected pixels become points.
struct ReprojectOptions {
    double max_range_m = 80.0;      ///< points farther than this from the camera are dropped, m
    double min_disparity_px = 0.0;  ///< disparities at or below this are dropped, px
    bool keep_void = true;          ///< keep points whose pixel has no palette class
    /// Throws std::invalid_argument naming the first bad field.
    void validate() const;
};

/// One point per pixel with a valid disparity within range, in the rectified left camera frame
/// (x right, y down, z forward, metres), coloured from `left` (grey or RGB) and labelled from
/// `classes` (an empty ClassImage labels everything void). Images must match the map's size.
LabeledCloud reproject(const DisparityMap& disparity, const StereoCamera& camera,
                       const ImageU8& left, const ClassImage& classes,
                       const ReprojectOptions& options);

}  // namespace cloud_analysis
