#pragma once

/// Metric reprojection of a disparity map with the Q matrix of the rig, and semantic
/// association of each point with the class of its pixel.

#include <Eigen/Core>

#include "cloud_analysis/cloud/semantic.hpp"
#include "cloud_analysis/cloud/types.hpp"
#include "cloud_analysis/io/io.hpp"

namespace cloud_analysis {

/// OpenCV's 4x4 reprojection matrix Q (Bradski & Kaehler, Learning OpenCV, ch. 12): maps
/// (u, v, d, 1) to homogeneous (X, Y, Z, W) in the rectified left camera frame, metres.
Eigen::Matrix4d reprojection_matrix(const StereoCamera& camera);

/// Which reprojected pixels become points.
struct ReprojectOptions {
    double max_range_m = 80.0;      ///< points farther than this from the camera are dropped, m
    double min_disparity_px = 0.0;  ///< disparities at or below this are dropped, px
    bool keep_void = true;          ///< keep points whose pixel has no palette class
    /// depth_edge_band's step: a pixel with one at least this much nearer within
    /// depth_edge_rows rows above or below is on a depth edge, metres; 0 = no band.
    double depth_edge_step_m = 0.8;
    int depth_edge_rows = 4;  ///< depth_edge_band's reach, rows: half the matching window
    /// Throws std::invalid_argument naming the first bad field.
    void validate() const;
};

/// The far side of depth steps across image rows: per pixel (v * width + u), 1 where a pixel of
/// the same column within `rows` rows above or below lies at least `step_m` nearer (depths
/// fb / (d - offset) of `border`), else 0. There the matching window straddles the two
/// surfaces and the disparity mixes them: the strip of a parked car that shows over the roof
/// of the nearer car before it is placed between the two. A surface seen along the viewing
/// ray changes depth across columns, not rows, so a side of a car is not on such an edge.
/// Empty when step_m <= 0 or rows <= 0.
std::vector<std::uint8_t> depth_edge_band(const DisparityMap& disparity, const MatchBorder& border,
                                          double step_m, int rows);

/// Which points of each palette class the entity extractor takes (see ClassPoints).
struct ClassSelection {
    /// Per palette class: keep pixel columns u with (u & column_mask) == 0, i.e.
    /// column_step - 1 for a power-of-two step; 0 keeps every column.
    std::vector<std::uint32_t> column_mask;
    std::vector<char> keep_pixels;  ///< per palette class: record each point's pixel
    /// The classes whose pixels are kept take pixels (u, v) with ((u | v) & lattice_mask) == 0:
    /// lattice step - 1 for a power-of-two step; 0 keeps every pixel.
    std::uint32_t lattice_mask = 0;
    double max_depth_m = 60.0;  ///< keep points with 0 < z < this, metres
};

/// ClassSelection's pixel rule: a point of a class at pixel (u, v) is taken when its column
/// passes the class's column_mask and, for a class on the lattice (its pixels kept), both u
/// and v pass the lattice mask.
inline bool pixel_taken(std::uint32_t column_mask, bool on_lattice, std::uint32_t lattice_mask,
                        std::uint32_t u, std::uint32_t v) {
    return (u & column_mask) == 0 && (!on_lattice || ((u | v) & lattice_mask) == 0);
}

/// One point per pixel with a valid disparity within range, in the rectified left camera frame
/// (x right, y down, z forward, metres), coloured from `left` (grey or RGB) and labelled from
/// `classes` (an empty ClassImage labels everything void). Images must match the map's size.
LabeledCloud reproject(const DisparityMap& disparity, const StereoCamera& camera,
                       const ImageU8& left, const ClassImage& classes,
                       const ReprojectOptions& options);

/// The extractor's points straight from the disparity, without building the cloud: equal to
/// reprojecting (as above) and splitting the cloud by class (points_by_class in extract.hpp)
/// with `selection`, at a fraction of the cost. `selection` has one entry per palette class;
/// class indices at or past it count as void.
ClassPoints reproject_by_class(const DisparityMap& disparity, const StereoCamera& camera,
                               const ClassImage& classes, const ReprojectOptions& options,
                               const ClassSelection& selection);

}  // namespace cloud_analysis
