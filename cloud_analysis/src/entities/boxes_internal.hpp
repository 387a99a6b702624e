#pragma once

// What boxes.cpp (the box fit) and box_heading.cpp (the heading of its footprint) share.

#include <cmath>
#include <optional>
#include <vector>

#include <Eigen/Core>

#include "cloud_analysis/entities/boxes.hpp"

namespace cloud_analysis {

/// A face along the viewing ray counts when a pixel of disparity moves its far end by at most
/// this share of its length.
constexpr double kAlongRaySmearShare = 0.1;

/// KITTI yaw of a heading given in ground (x, z) coordinates, front/back resolved to z >= 0.
double yaw_of(Eigen::Vector2d heading_xz);

/// Angle in [0, pi/2) of the first rectangle axis maximising Zhang et al.'s closeness score,
/// skipping axes within `tolerance` of `blocked` (modulo 90 degrees; NaN: none).
double best_lshape_angle(const std::vector<Eigen::Vector2d>& pts, double step_deg,
                         double blocked = std::nan(""), double tolerance = 0.0);

/// As best_lshape_angle for weighted points (each point's closeness term times its weight),
/// searched coarse to fine: kCoarseStepDeg steps over 90 degrees, then step_deg steps within
/// one coarse step of the best (29 passes instead of 90 at 1 degree).
double best_weighted_lshape_angle(const std::vector<Eigen::Vector2d>& pts,
                                  const std::vector<float>& weights, double step_deg,
                                  double blocked = std::nan(""), double tolerance = 0.0);

/// As best_lshape_angle for many points. Points above one another share a footprint position:
/// they are counted on a fine grid over the cluster's footprint and searched with the counts as
/// weights, which scores like every point at a fraction of the cost and whatever their order (a
/// strided sample scored differently and moved headings by degrees).
double best_gridded_lshape_angle(const std::vector<Eigen::Vector2d>& ab, double step_deg,
                                 double blocked, double tolerance);

/// The angle of a straight face of the footprint points `ab` that is a long side (see
/// fit_upright_box): across the viewing ray (more than 45 degrees from it), or along it where
/// range smear is small, holding options.face_share of the points and longer than 1.2 prior
/// widths; nothing without one, with an imposed yaw, or with the rule off.
std::optional<double> long_face_angle(const std::vector<Eigen::Vector2d>& ab,
                                      const BoxFitOptions& options);

}  // namespace cloud_analysis
