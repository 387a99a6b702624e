#pragma once

/// Dropping thing candidates that are not objects of their own (wrong-match shadows and edge
/// smear behind nearer things, fragments nested in larger things) and stuff entities smeared
/// onto things' silhouettes.

#include <cstdint>
#include <optional>
#include <vector>

#include <scene_schema/entities.hpp>

#include "cloud_analysis/entities/candidate.hpp"
#include "cloud_analysis/support/box_axes.hpp"

namespace cloud_analysis::instances {

/// Image-space suppression of "shadows" (candidates visited nearest first, tested against the
/// accepted ones of other groups nearer by more than min_gap_m):
/// - a candidate with most of its pixels inside the row extents of a nearer candidate (its
///   leftmost to rightmost pixel on each row) is dropped: pixels
///   interleaved with a nearer object's are wrong matches on it (dark, textureless car bodies,
///   holes in its disparity) reprojected too far. A real object behind another is occluded
///   there and shows only beside it, so a candidate beside a nearer one is kept;
/// - a fragment (short or sparse) is dropped when most of its pixels lie within radius_px of
///   those extents on any row within radius_px above or below: stereo smear along a nearer
///   object's edges (roof lines matched to the background) is a thin strip beside it.
/// Pieces of one group (a parked row cut at clear gaps) never suppress each other: each is a
/// distinct object and the row is connected in space, which a shadow is not.
std::vector<Candidate> suppress_shadows(std::vector<Candidate> candidates,
                                        const std::vector<std::uint32_t>& pixels,
                                        const PixelGrid& grid, double min_gap_m,
                                        double max_shared_fraction, int radius_px);

/// Median over the image rows a candidate's pixels cover of its pixels on the row: its width in
/// the image, pixels (0 without pixels).
double median_row_width_px(const Indices& members, const std::vector<std::uint32_t>& pixels,
                           const PixelGrid& grid);

/// Drops thing candidates narrower in the image than min_width_px (median_row_width_px): a
/// strip a few pixels wide along an object's outline is label bleed (a hand-drawn mask reaching
/// over the background) or edge smear, reprojected at the background's depth; an object, even
/// a far car (26 px at 50 m) or one seen only over a nearer car's roof, is wider.
std::vector<Candidate> drop_strips(std::vector<Candidate> candidates,
                                   const std::vector<std::uint32_t>& pixels, const PixelGrid& grid,
                                   double min_width_px);

/// Drops thing candidates narrower in the image than width_px (median_row_width_px) that lie
/// along a larger candidate of the class: at least half their pixels within radius_px of that
/// candidate's column extent on the same image row, and its range differing by at least
/// min_gap_m. Such a strip is the outline of the larger thing at another object's depth:
/// label bleed over the background behind it, or a nearer pole's or tree's disparity smeared
/// over its pixels. A far car on its own, however narrow, lies beside no larger one; pieces of
/// one group (a row cut at clear gaps, whose sparse far end may be narrow) never drop each
/// other.
std::vector<Candidate> drop_strips_beside(std::vector<Candidate> candidates,
                                          const std::vector<std::uint32_t>& pixels,
                                          const PixelGrid& grid, double width_px, int radius_px,
                                          double min_gap_m);

/// Drops thing candidates whose centre lies inside the footprint of a candidate with more
/// points: two objects cannot overlap that much, so the smaller is a fragment of the larger.
std::vector<Candidate> suppress_nested(std::vector<Candidate> candidates);

/// A thing's bird's-eye footprint: centre, heading's cosine and sine, half length and width.
struct Footprint {
    double x, z;            ///< centre, metres
    BoxAxes axes;           ///< its heading
    double half_L, half_W;  ///< half length and width, metres
    /// Bird's-eye distance of the point (x, z) from the footprint, metres; 0 inside.
    double distance_m(double px, double pz) const;
};

/// The footprint of a box.
Footprint footprint_of(const OrientedBox& box);

/// The footprints of thing entities.
std::vector<Footprint> footprints_of(const std::vector<scene_schema::Entity>& things);

/// Share of the bird's-eye footprint of `e` (sampled on a 10 x 10 grid of cell centres) inside
/// any of the `things` footprints.
double footprint_share_inside(const scene_schema::Entity& e, const std::vector<Footprint>& things);

/// Objects of an instance image cannot share ground: an object's box (Candidate::instance)
/// with more than a quarter of its footprint inside the other objects' boxes is fitted again
/// with its heading turned a quarter turn (`fit` with yaw_rad imposed) when that at least halves
/// the share. The end face of a car seen front-on does not tell its heading by itself; its
/// neighbours side by side in a row do. Candidates without an object are left alone.
void turn_overlapping_objects(std::vector<Candidate>& candidates,
                              const std::vector<Eigen::Vector3f>& pts, BoxFitOptions fit,
                              const std::optional<GroundPlane>& ground);

}  // namespace cloud_analysis::instances
