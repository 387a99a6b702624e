#pragma once

/// Splitting a thing blob that is too large for its class's prior into the things it holds:
/// a parked row end to end, things side by side seen front-on, or two things merged across.

#include <optional>
#include <vector>

#include <Eigen/Core>

#include "cloud_analysis/entities/candidate.hpp"
#include "cloud_analysis/entities/extract.hpp"

namespace cloud_analysis::instances {

/// Pieces of a split blob; at_gaps when every cut fell in a clear gap (a bin with at most a
/// quarter of the median occupied bin's points): the pieces are then distinct objects.
struct Split {
    std::vector<Indices> parts;     ///< the pieces' points
    bool at_gaps = false;           ///< every cut in a clear gap
    std::optional<double> yaw_rad;  ///< heading imposed on the pieces (cars side by side)
    bool row_pieces = false;        ///< the pieces of a row's partition: not cut along it again
};

/// Pieces of a thing whose box is much longer or wider than its prior (a parked row, or
/// cars side by side merged by the semantic image); {idx} when it fits the prior.
Split split_oversized(const std::vector<Eigen::Vector3f>& pts, const Indices& idx,
                      const OrientedBox& box, const ClassSettings& s,
                      const std::optional<GroundPlane>& ground, const ExtractOptions& options,
                      bool truncated = false, bool row_piece = false);

/// Pairs of pieces of one cluster each too faint to be a thing (seen over less than
/// min_seen_area_m2) that lie end to end along the first one's heading (at most
/// `row_gap_m` apart between their 2-98 % extents, their medians across it within half the
/// prior width, both within one prior length) and together are not faint: a thing the row's
/// cuts left in two, such as a car 28 % visible behind a van whose first metre went with the
/// van's piece. Each piece joins at most once, with the nearest such piece. Returns the joined
/// points, and removes the pieces joined from `candidates`.
std::vector<Indices> join_faint_pieces(const std::vector<Eigen::Vector3f>& pts,
                                       std::vector<Candidate>& candidates, const ClassSettings& s,
                                       const ExtractOptions& options);

/// Vertical extent of points (2 % to 98 % height quantiles above the ground, or along -y
/// without a ground plane), metres.
double height_spread(const std::vector<Eigen::Vector3f>& pts, const Indices& idx,
                     const std::optional<GroundPlane>& ground);

}  // namespace cloud_analysis::instances
