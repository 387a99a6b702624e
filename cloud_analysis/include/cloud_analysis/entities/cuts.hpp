#pragma once

/// Where a thing is cut in the image, so that its box is completed beyond the cut: by the edge
/// of what stereo sees, or by something nearer standing in front of it (used by the thing
/// classes of the "instances" extractor, things.cpp).

#include <cstdint>
#include <optional>
#include <utility>
#include <vector>

#include <Eigen/Core>

#include "cloud_analysis/entities/candidate.hpp"

namespace cloud_analysis::instances {

/// The camera-frame (x, z) mean of the points in the outermost kEdgeColumns columns of what
/// stereo sees (the image's edges, or the border the matcher leaves without disparity: the
/// grid's first and last columns with points, and on the left the column below which nothing
/// at the point's own depth has a match in the right image) when that edge cuts the points (at
/// least kMinEdgePoints of them there; the side with more); nullopt otherwise or when the
/// pixels are unknown.
std::optional<Eigen::Vector2d> truncation_point(const std::vector<Eigen::Vector3f>& pts,
                                                const std::vector<std::uint32_t>& pixels,
                                                const PixelGrid& grid, const Indices& members);

/// Where an object of the instance image is cut by something standing in front of it (depths
/// from PixelGrid::depth_m): per image row, the first pixel beyond the object's outermost
/// member, past its own pixels and pixels at its own depth (its labels may fall short of its
/// outline), that lies a step deeper or nearer (0.3 m, or two disparity noises of 0.5 px) within
/// 12 columns. The side (left -1, right +1) where most of at least 5 such rows are nearer, when
/// only one is, with the camera-frame (x, z) mean of those rows' outermost members; nullopt
/// otherwise or without depths. Its hidden part may lie beyond that cut (Hoiem, Efros, Hebert,
/// "Recovering Occlusion Boundaries", IJCV 2011: an outline is owned by the nearer surface).
std::optional<std::pair<Eigen::Vector2d, int>> occlusion_cut(
    const std::vector<Eigen::Vector3f>& pts, const std::vector<std::uint32_t>& pixels,
    const PixelGrid& grid, const Indices& members, std::uint32_t instance);

}  // namespace cloud_analysis::instances
