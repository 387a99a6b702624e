#pragma once

/// Where a thing is cut in the image, so that its box is completed beyond the cut: by the edge
/// of what stereo sees, or by something nearer standing in front of it (used by the thing
/// classes of the "instances" extractor, things.cpp).

#include <array>
#include <cstdint>
#include <optional>
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

/// Where an object of the instance image is cut by something standing in front of it.
struct OcclusionCut {
    Eigen::Vector2d xz;  ///< camera-frame (x, z) mean of the cut rows' outline points
    int side = 0;        ///< the side the hidden part lies on in the image: -1 left, +1 right
};

/// The occlusion cut of an object of the instance image (depths from PixelGrid::depth_m): per
/// image row and side, the object's outline is its outermost member past those with a nearer
/// thing's disparity (up to the first step to a farther depth between neighbouring members
/// among the 8 outermost: foreground fattening, labels past the outline); the row is cut when the
/// first pixel beyond it, past the object's own pixels and pixels at its depth, within 12
/// columns, is a step nearer (0.3 m, or two disparity noises of 0.5 px). The side where most of
/// at least 5 such rows are cut, when only one is; nullopt otherwise or without depths.
/// `bleed`, when given, receives the members before the outline on the cut rows (sorted);
/// `sides_cut`, when given, whether each side (left, right) is cut, both included. The
/// hidden part may lie beyond the cut (Hoiem, Efros, Hebert, "Recovering Occlusion
/// Boundaries", IJCV 2011: an outline is owned by the nearer surface).
std::optional<OcclusionCut> occlusion_cut(const std::vector<Eigen::Vector3f>& pts,
                                          const std::vector<std::uint32_t>& pixels,
                                          const PixelGrid& grid, const Indices& members,
                                          std::uint32_t instance, Indices* bleed = nullptr,
                                          std::array<bool, 2>* sides_cut = nullptr);

/// The members of an object of the instance image that show something standing in front of it
/// inside its outline (a pole, a trunk, a person, and the labels that bled over them): per image
/// row, its members by column split into runs where neighbouring members' depths step apart
/// (0.3 m, or two disparity noises of 0.5 px, as occlusion_cut); a run between two others and
/// nearer than both by such a step. An object's own surface seen from outside it holds no
/// nearer island (Hoiem, Efros, Hebert, IJCV 2011: an outline is owned by the nearer surface).
/// Empty when the pixels are unknown; sorted.
Indices occluders_inside(const std::vector<Eigen::Vector3f>& pts,
                         const std::vector<std::uint32_t>& pixels, const PixelGrid& grid,
                         const Indices& members);

}  // namespace cloud_analysis::instances
