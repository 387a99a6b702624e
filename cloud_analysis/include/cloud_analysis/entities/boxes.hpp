#pragma once

/// Upright oriented boxes: footprint by L-shape fitting (Zhang et al., "Efficient L-Shape
/// Fitting for Vehicle Detection Using Laser Scanners", IV 2017, closeness criterion) in the
/// ground plane, completion with a class size prior away from the camera, and the thesis's
/// one-box-per-class extractors (centre of mass, average box, variance box).

#include <array>
#include <optional>
#include <vector>

#include <Eigen/Core>

#include "cloud_analysis/entities/ground.hpp"

namespace cloud_analysis {

/// An upright box in the camera frame (KITTI convention, centre of the box).
struct OrientedBox {
    Eigen::Vector3d centre_m = Eigen::Vector3d::Zero();  ///< box centre, metres
    double theta = 0.0;  ///< yaw about +y, heading (cos t, 0, -sin t), radians
    double L_m = 1.0;    ///< length along the heading, metres
    double W_m = 1.0;    ///< width across the heading, metres
    double H_m = 1.0;    ///< height, metres
};

/// Settings of fit_upright_box.
struct BoxFitOptions {
    double prior_L_m = 0.0;       ///< class length prior, metres (0 = no completion)
    double prior_W_m = 0.0;       ///< class width prior, metres (0 = no completion)
    double prior_H_m = 0.0;       ///< class height prior, metres (0 = observed height)
    double angle_step_deg = 1.0;  ///< L-shape search step, degrees, in (0, 10]
    double min_extent_m = 0.05;   ///< smallest box side, metres, > 0
    double trim_fraction = 0.02;  ///< fraction of points trimmed at each end per axis, [0, 0.2)
    /// Fraction trimmed instead at the end nearer the camera of an axis within 45 degrees of
    /// the viewing ray: stereo spreads a face along the ray both ways, so the nearest points
    /// of a near face lie in front of it, [trim_fraction, 0.2) (trim_fraction = no change).
    double near_trim_fraction = 0.02;
    /// Footprint extents as quantiles of seen surface, not of points: each point weighs its
    /// squared range from the camera's foot, so that a side seen along the viewing ray, whose
    /// far metres hold few pixels, is trimmed by the same length at both ends. Ranges are
    /// capped at the points' near end plus the longer prior (smear and the next thing of a row
    /// beyond it weigh no more) and, with disparity_fb_px_m, at the range where one pixel of
    /// disparity spans a tenth of prior_L_m (smear, not pixel spacing, shapes the far end there).
    bool area_weighted_extents = false;
    bool rest_on_ground = true;     ///< bottom on the plane (else the lowest point)
    double face_tolerance_m = 0.2;  ///< distance of a point from a straight face, metres, > 0
    double face_share = 0.5;        ///< a straight face across the viewing ray holding this
                                    ///< share of the points and longer than 1.2 prior widths
                                    ///< is a long side, [0, 1] (0 = off)
    /// Focal length times baseline of the rig (the disparity of depth z is fb / z), px m: a
    /// face along the viewing ray also counts as a long side when one pixel of disparity moves
    /// its far end by at most a tenth of its length and of prior_L_m (a near car's side: range
    /// smear lines points up along rays only farther out); 0 = unknown, only faces across the
    /// ray.
    double disparity_fb_px_m = 0.0;
    /// When only a short face is seen (no side longer than 1.3 prior widths): false, the length
    /// runs along the footprint axis nearer the viewing ray (a piece of a thing, likely its end
    /// seen from behind); true, along the face's normal, the axis the points extend less along
    /// (a whole object: the face it shows is an end, whatever the angle it is seen at), unless
    /// the image's edge cuts it (truncation_xz).
    bool short_face_is_end = false;
    std::optional<double> yaw_rad;  ///< heading imposed instead of the L-shape search, radians
                                    ///< (cars cut from a row seen front-on), finite
    /// Camera-frame (x, z) mean of the points in the image's outermost columns when the image's
    /// left or right edge cuts them: the cut is a straight edge of points along the border's
    /// ray, not a face, so the L-shape search skips rectangle axes within
    /// truncation_exclusion_deg of that ray, and the prior completes each side beyond the image
    /// edge (where the hidden part is), not away from the camera.
    std::optional<Eigen::Vector2d> truncation_xz;
    /// The side of truncation_xz's ray the hidden part lies on, as seen in the image: -1 left
    /// (smaller columns), +1 right, 0 away from the optical axis (an image edge). A thing whose
    /// outline ends where something nearer stands in front of it is cut there the same way, but
    /// its points do not line up along the cut: no axis is skipped for it.
    int truncation_side = 0;
    double truncation_exclusion_deg = 20.0;  ///< that exclusion, degrees, [0, 45)
    /// Throws std::invalid_argument naming the bad field.
    void validate() const;
};

/// Fits an upright box to points (camera frame). With a ground plane the box stands on it;
/// with priors the footprint is completed away from the camera. theta is in [-pi, 0]: the
/// heading is the one of the two opposite directions pointing away from the camera (z >= 0).
OrientedBox fit_upright_box(const std::vector<Eigen::Vector3f>& points_m,
                            const std::optional<GroundPlane>& ground, const BoxFitOptions& options);

/// The footprint axis a fit chose: its angle in the ground frame and whether a long straight
/// face set it (then the face is the box's length). It depends on the points, the ground, the
/// truncation, yaw, angle-step, face and prior settings, not on the extents' trimming.
struct FootprintAxis {
    double angle_rad = 0.0;
    bool face_is_length = false;
};

/// fit_upright_box, also giving the footprint axis it chose.
OrientedBox fit_upright_box(const std::vector<Eigen::Vector3f>& points_m,
                            const std::optional<GroundPlane>& ground, const BoxFitOptions& options,
                            FootprintAxis& axis);

/// fit_upright_box on the footprint axis an earlier fit of the same points and ground chose
/// with the same axis settings (a refit that changes only how the extents are trimmed or
/// weighted: near_trim_fraction, area_weighted_extents), without searching it again.
OrientedBox fit_upright_box_on_axis(const std::vector<Eigen::Vector3f>& points_m,
                                    const std::optional<GroundPlane>& ground,
                                    const BoxFitOptions& options, const FootprintAxis& axis);

/// As fit_upright_box for weighted points, each standing for `weight` points at its place
/// (voxel centroids weighted by their point counts, so that a stuff cluster costs its voxels,
/// not its points): closeness terms and quantiles are weighted, and the L-shape angle is
/// searched in 5 degree steps, then in angle_step_deg steps within 5 degrees of the best. No
/// straight-face rule (it counts points); weights finite and > 0, one per point.
OrientedBox fit_upright_box_weighted(const std::vector<Eigen::Vector3f>& points_m,
                                     const std::vector<float>& weights,
                                     const std::optional<GroundPlane>& ground,
                                     const BoxFitOptions& options);

/// The box at length_m along its heading, its end nearer the camera kept in place, or its end
/// farther from it when keep_far_end.
OrientedBox with_length(const OrientedBox& box, double length_m, bool keep_far_end);

/// The box with the far end of its length moved to where the outermost pixel column of its
/// points (the ray of slope x / z that a point's own column gives) meets its side: a side seen
/// along the viewing ray ends sharply in the image (about 15 columns per metre at 14 m, 4 m
/// aside) while its range is smeared by a metre there, so its far metre holds too few points
/// for the box's quantiles. The side is the box's side facing the camera. Moved outwards, never
/// beyond the points' own farthest extent along the length, to a length of at most
/// max_length_m. With `own_outline` (an instance image: the outermost points are the thing's
/// own), the side is the line along the heading through the median position of the outermost
/// points when that lies within 0.2 m of the box's side (a car's side tapers towards its ends;
/// farther in, they are range smear), and the far end also moves inwards when the
/// image side it comes from (left, right) is true there (nothing nearer hides the outline), never
/// in front of the max(10, n / 500)-th farthest point. The box unchanged when its length
/// runs across the viewing ray (more than 45 degrees from it), when the outermost ray meets
/// the side at less than 10 degrees, or with fewer than 20 points. The outermost column is the
/// max(10, n / 500)-th point from the edge (stray points).
OrientedBox far_end_to_columns(
    const OrientedBox& box, const std::vector<Eigen::Vector3f>& points_m, double max_length_m,
    const std::optional<std::array<bool, 2>>& own_outline = std::nullopt);

/// Heading yaw (radians, [-pi, 0]) of the best L-shape footprint of points given in the
/// (x, z) plane; exposed for tests.
double lshape_yaw(const std::vector<Eigen::Vector2d>& xz_m, double angle_step_deg);

/// Thesis extractors (one box per class, theta 0).
/// Centre of mass: the mean of the points, size given by the caller.
OrientedBox centroid_box(const std::vector<Eigen::Vector3f>& points_m,
                         const Eigen::Vector3d& size_LHW_m);
/// Average box: per axis direction the mean offset of the points on that side of the centre,
/// times 2, is the half-extent on that side (a uniform box gives its own size).
OrientedBox average_box(const std::vector<Eigen::Vector3f>& points_m);
/// Variance box: extent 2 * sqrt(3) * sigma per axis (exact for a uniform distribution).
OrientedBox variance_box(const std::vector<Eigen::Vector3f>& points_m);

}  // namespace cloud_analysis
