#pragma once

/// The points of a thing that are not its surface: stereo smear behind it along the viewing
/// rays and mixed disparities on the far side of depth steps (used by the thing classes of the
/// "instances" extractor, things.cpp).

#include <cstdint>
#include <optional>
#include <vector>

#include <Eigen/Core>

#include "cloud_analysis/entities/candidate.hpp"

namespace cloud_analysis::instances {

/// Drops stereo smear behind a thing: per viewing direction (0.5 degree azimuth bins), points
/// farther (bird's-eye range) than the nearest one plus the prior's diagonal plus a margin;
/// and points implausibly high above or below the ground. `behind`, when given, receives the
/// points dropped for their range.
Indices drop_outliers(const std::vector<Eigen::Vector3f>& pts, const Indices& idx,
                      const ClassSettings& s, const std::optional<GroundPlane>& ground,
                      double margin_m, Indices* behind = nullptr);

/// The members whose pixels are not on the far side of a depth step (PixelGrid::depth_edge),
/// when at least min_points of them remain (the others in `on_edge`); all of them otherwise (a
/// thing seen only as a strip over a nearer one has nothing better).
Indices off_depth_edges(const std::vector<std::uint32_t>& pixels, const PixelGrid& grid,
                        Indices members, const ClassSettings& s, Indices& on_edge);

/// The points on a depth edge that a cluster's boxes were fitted without, each given back to
/// the candidate whose box footprint lies nearest it, within kEdgePointReach: they are seen
/// surface of that thing, at a mixed depth, and count as such (point count, seen area, image
/// extent) though they do not shape its box. Farther ones are dropped.
void give_back_edge_points(const std::vector<Eigen::Vector3f>& pts, const Indices& on_edge,
                           std::vector<Candidate>& candidates);

}  // namespace cloud_analysis::instances
