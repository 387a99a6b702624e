#pragma once

// What row_split.cpp (the cuts of a blob) and row_profiles.cpp (the height profiles that say
// where a row's things meet) share.

#include <vector>

#include <Eigen/Core>

#include "cloud_analysis/entities/row_split.hpp"

namespace cloud_analysis::instances {

/// A bin holding at most this share of the median occupied bin's points is a clear gap.
constexpr double kGapFraction = 0.25;

/// The points' coordinates along the unit direction (dir_x, dir_z) and their range.
struct Projection {
    std::vector<double> along;
    double lo = 1e300, hi = -1e300;
};

Projection project(const std::vector<Eigen::Vector3f>& pts, const Indices& idx, double dir_x,
                   double dir_z);

/// The top profile of a blob along its length, in bins from the lowest along-coordinate.
struct TopProfile {
    std::vector<double> top;  ///< per bin, its points' 90 % height above the ground after a
                              ///< closing over `closing` bins either side, metres; -1 unknown
                              ///< (fewer than 3 points)
    std::vector<int> count;   ///< points per bin
};

/// The top profile of the points idx (their along-coordinates `along`) in bins of bin_m from
/// lo to hi.
TopProfile top_profile(const std::vector<Eigen::Vector3f>& pts, const Indices& idx,
                       const std::vector<double>& along, const GroundPlane& ground, double bin_m,
                       double lo, double hi, int closing);

/// The lower of the highest tops of a top profile within `reach` bins before bin b and within
/// `reach` bins after it (-1 where a side has none): how high a valley at b is flanked.
double flanking_peak(const std::vector<double>& top, int b, int reach);

/// A valley of a top profile: a run of bins whose top lies at least a depth below their
/// flanking peaks (flanking_peak), both reaching a height.
struct ValleyRun {
    int deepest;   ///< its deepest bin (the first of equals)
    int first;     ///< first and last bin of the run's part below half its depth, bins with
    int last;      ///< no top included
    double depth;  ///< the deepest bin's depth below its flanking peak, metres
};

/// The valleys of a top profile, in order: runs of bins with a top at least min_depth_m below
/// their flanking peak within `reach` bins, that peak reaching min_peak_m.
std::vector<ValleyRun> valley_runs(const std::vector<double>& top, int reach, double min_depth_m,
                                   double min_peak_m);

/// Whether a long blob is a row of things side by side seen front-on (or from behind) rather
/// than one thing seen side-on: its length along the box heading spans at least two prior
/// widths, and across the heading, from the camera's side, its top stays below
/// low_fraction * its highest top for at least low_extent_m (the bonnets in front of the
/// windscreens), over the whole blob and in most slices one prior width long along it (each
/// thing of the row has its bonnet: a thing seen side-on under a heading a little off its own
/// shows its low end across the near side of the blob, but not slice by slice, where its side
/// shows its roof line).
bool front_on_row(const std::vector<Eigen::Vector3f>& pts, const Indices& idx,
                  const OrientedBox& box, const ClassSettings& s, const GroundPlane& ground,
                  const ExtractOptions& options);

/// Pieces of a blob cut along (dir_x, dir_z) at the valleys of its top profile (things parked
/// end to end, their roofs higher than the ends where they meet); empty without a valley.
std::vector<Indices> split_at_valleys(const std::vector<Eigen::Vector3f>& pts, const Indices& idx,
                                      double dir_x, double dir_z, const ClassSettings& s,
                                      const GroundPlane& ground, const ExtractOptions& options);

/// The things of a row of the size-family class (cars and vans) parked end to end along
/// (dir_x, dir_z) (ExtractOptions::row_model "partition"; docs/entities.md): the row (its fitted
/// box, centred at `centre_along` and `length_m` long, and the points beyond its far end) is cut
/// into pieces, each a thing or nothing, that maximise the sum of the things' length
/// log-likelihoods, the evidence of the cuts that end them (valleys and gaps of the top profile)
/// and the cost of the surface left to nothing: a dynamic programme over the cut sites. The things'
/// points; empty when the whole row is one thing. With `near_end_cut`, the image's edge cuts the
/// row's near end. `apart`: whether every two things that meet do so at a gap or a valley (the
/// pieces are a row of distinct things, none the shadow of another).
std::vector<Indices> partition_row(const std::vector<Eigen::Vector3f>& pts, const Indices& idx,
                                   double dir_x, double dir_z, double centre_along, double length_m,
                                   const ClassSettings& s, const GroundPlane& ground,
                                   const ExtractOptions& options, bool near_end_cut, bool& apart);

}  // namespace cloud_analysis::instances
