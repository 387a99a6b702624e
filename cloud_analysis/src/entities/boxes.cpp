#include "cloud_analysis/entities/boxes.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <utility>

#include <Eigen/Geometry>

#include "boxes_internal.hpp"
#include "cloud_analysis/support/select.hpp"
#include "stereoscene/support/angles.hpp"

namespace cloud_analysis {
namespace {

using stereoscene::support::kPi;
/// An axis whose component of an image edge's outward normal is below this runs along the edge.
constexpr double kEdgeAxisShare = 0.2;
/// A thing cut by an image edge is not completed beyond it along an axis when this share of the
/// part added or more lies in view.
constexpr double kSeenAddedShare = 0.25;

/// Orthonormal ground-aligned basis: up = plane normal, ex ~ camera x, ez ~ camera z.
struct GroundFrame {
    Eigen::Vector3d up{0.0, -1.0, 0.0};
    Eigen::Vector3d ex{1.0, 0.0, 0.0};
    Eigen::Vector3d ez{0.0, 0.0, 1.0};
    double d = 0.0;  ///< plane offset: height(p) = up . p + d

    explicit GroundFrame(const std::optional<GroundPlane>& ground) {
        if (ground) {
            up = ground->normal.normalized();
            d = ground->d;
        }
        ex = (Eigen::Vector3d::UnitX() - up.x() * up).normalized();
        ez = up.cross(ex);
    }
    Eigen::Vector2d footprint(const Eigen::Vector3d& p) const { return {ex.dot(p), ez.dot(p)}; }
    double height(const Eigen::Vector3d& p) const { return up.dot(p) + d; }
    Eigen::Vector3d to_camera(const Eigen::Vector2d& ab, double h) const {
        return ab.x() * ex + ab.y() * ez + (h - d) * up;
    }
};

using WeightedValues = std::vector<std::pair<double, float>>;

/// The value of rank `rank` (0-based) among weighted values written out (each value standing
/// for `weight` equal ones), found by halving the range with nth_element (linear time, the
/// same value as a full sort gives); the values are reordered.
double weighted_rank_value(WeightedValues::iterator first, WeightedValues::iterator last,
                           double rank) {
    const auto by_value = [](const auto& a, const auto& b) { return a.first < b.first; };
    while (last - first > 1) {
        const auto mid = first + (last - first) / 2;
        std::nth_element(first, mid, last, by_value);
        double below = 0.0;
        for (auto it = first; it != mid; ++it) below += double{it->second};
        if (rank < below) {
            last = mid;
        } else if (rank < below + double{mid->second}) {
            return mid->first;
        } else {
            rank -= below + double{mid->second};
            first = mid + 1;
        }
    }
    return first->first;
}

/// Values at fractions q_lo <= q_hi (0..1) of weighted values, each value standing for
/// `weight` equal ones (reordered): the values of ranks round(q * (W - 1)) among the W
/// values so stood for, as quantiles() takes of the values written out.
std::pair<double, double> weighted_quantiles(WeightedValues& values, double q_lo, double q_hi) {
    if (values.empty()) return {0.0, 0.0};
    double total = 0.0;
    for (const auto& v : values) total += double{v.second};
    const double rank_lo = std::round(std::clamp(q_lo, 0.0, 1.0) * (total - 1.0));
    const double rank_hi = std::round(std::clamp(q_hi, 0.0, 1.0) * (total - 1.0));
    return {weighted_rank_value(values.begin(), values.end(), rank_lo),
            weighted_rank_value(values.begin(), values.end(), rank_hi)};
}

/// Interval [lo, hi] grown to `size` away from the camera (at coordinate 0 on the axis); on
/// both ends alike when the camera faces the interval (a face seen across the viewing ray
/// and cut short by an occluder or the image edge: the hidden end is unknown).
void complete_away(double& lo, double& hi, double size) {
    if (hi - lo >= size) return;
    if (lo < 0.0 && hi > 0.0) {
        const double grow = (size - (hi - lo)) / 2.0;
        lo -= grow;
        hi += grow;
    } else if (lo + hi >= 0.0) {
        hi = lo + size;
    } else {
        lo = hi - size;
    }
}

/// Interval [lo, hi] along an axis grown to `size` towards the image edge that cuts the object:
/// `outward` is the axis's component of the edge's outward normal (the hidden part lies beyond
/// the edge). An axis nearly parallel to the edge (|outward| < kEdgeAxisShare) is completed
/// away from the camera as usual.
void complete_beyond_edge(double& lo, double& hi, double size, double outward) {
    if (std::abs(outward) < kEdgeAxisShare) {
        complete_away(lo, hi, size);
    } else if (hi - lo < size) {
        if (outward > 0.0) {
            hi = lo + size;
        } else {
            lo = hi - size;
        }
    }
}

/// Share of the rectangle [a0, a1] along e by [b0, b1] along e_other (ground coordinates from
/// the camera's foot) on the optical axis's side of an image edge's ray through the camera's
/// foot, whose outward normal is `outward`: sampled on a 5 x 5 grid.
double share_in_view(double a0, double a1, const Eigen::Vector2d& e, double b0, double b1,
                     const Eigen::Vector2d& e_other, const Eigen::Vector2d& outward) {
    constexpr int kSamples = 5;
    int inside = 0;
    for (int i = 0; i < kSamples; ++i) {
        for (int j = 0; j < kSamples; ++j) {
            const Eigen::Vector2d p = (a0 + (i + 0.5) / kSamples * (a1 - a0)) * e +
                                      (b0 + (j + 0.5) / kSamples * (b1 - b0)) * e_other;
            inside += outward.dot(p) < 0.0 ? 1 : 0;
        }
    }
    return static_cast<double>(inside) / (kSamples * kSamples);
}

/// Interval [lo, hi] along axis e of a thing cut by an image edge (outward normal `outward`;
/// [other_lo, other_hi] its extent along the other axis) grown to `size`: beyond the edge unless
/// a quarter or more of the part so added lies inside the field of view, where it would have
/// been seen. The edge then cuts the thing's other side (a car ahead by the edge shows its whole
/// rear or front, and only that face's far corner is cut), and the interval grows away from the
/// camera.
void complete_at_edge(double& lo, double& hi, double size, const Eigen::Vector2d& e,
                      double other_lo, double other_hi, const Eigen::Vector2d& e_other,
                      const Eigen::Vector2d& outward) {
    const double across = outward.dot(e);
    double beyond_lo = lo, beyond_hi = hi;
    complete_beyond_edge(beyond_lo, beyond_hi, size, across);
    if (std::abs(across) >= kEdgeAxisShare && beyond_hi - beyond_lo > hi - lo &&
        share_in_view(beyond_lo < lo ? beyond_lo : hi, beyond_lo < lo ? lo : beyond_hi, e, other_lo,
                      other_hi, e_other, outward) >= kSeenAddedShare) {
        complete_away(lo, hi, size);
    } else {
        lo = beyond_lo;
        hi = beyond_hi;
    }
}

/// complete_at_edge for an image edge. For an occluder (`occluder`): the end beside it is either
/// the thing's own or hidden behind it, and nothing in the points tells which, so the missing
/// length is shared between growing beyond the cut and away from the camera (the centre that
/// is off by at most half the missing length either way).
void complete_cut(double& lo, double& hi, double size, const Eigen::Vector2d& e, double other_lo,
                  double other_hi, const Eigen::Vector2d& e_other, const Eigen::Vector2d& outward,
                  bool occluder) {
    double beyond_lo = lo, beyond_hi = hi;
    complete_at_edge(beyond_lo, beyond_hi, size, e, other_lo, other_hi, e_other, outward);
    if (!occluder) {
        lo = beyond_lo;
        hi = beyond_hi;
        return;
    }
    complete_away(lo, hi, size);
    lo = 0.5 * (lo + beyond_lo);
    hi = 0.5 * (hi + beyond_hi);
}

/// Extents of the points along the footprint axes and of their heights (trimmed quantiles).
struct Extents {
    double lo1, hi1;               ///< along e1, metres from the camera's foot
    double lo2, hi2;               ///< along e2, metres
    double bottom_seen, top_seen;  ///< heights above the ground plane, metres
};

/// The box of footprint axes e1, e2 and their extents: picks the length axis (the longer, or
/// the one closer to the viewing ray when only a short face of a thing is seen, or e1 when it
/// is a face), completes the sides with the priors away from the camera and returns the box in
/// the camera frame.
OrientedBox assemble_box(const GroundFrame& frame, bool has_ground, const BoxFitOptions& options,
                         bool face_is_length, Eigen::Vector2d e1, Eigen::Vector2d e2, Extents x) {
    double &lo1 = x.lo1, &hi1 = x.hi1, &lo2 = x.lo2, &hi2 = x.hi2;
    // Axis 1 becomes the length axis; swap when axis 2 should be.
    bool swap = !options.yaw_rad && (hi2 - lo2) > (hi1 - lo1);
    if (face_is_length) swap = false;
    if (!options.yaw_rad && !face_is_length && options.prior_L_m > 0.0 && options.prior_W_m > 0.0) {
        const double longest = std::max(hi1 - lo1, hi2 - lo2);
        if (longest <= 1.3 * options.prior_W_m) {
            // Only a short face is seen: it is most likely the rear or front, so the length
            // runs along the viewing ray.
            const Eigen::Vector2d centre = ((lo1 + hi1) / 2.0) * e1 + ((lo2 + hi2) / 2.0) * e2;
            const Eigen::Vector2d ray = centre.normalized();
            // A face cut by the image's edge may be a side running out of the image.
            swap = options.short_face_is_end &&
                           !(options.truncation_xz && options.truncation_side == 0)
                       ? (hi2 - lo2) < (hi1 - lo1)
                       : std::abs(ray.dot(e2)) > std::abs(ray.dot(e1));
        }
    }
    if (swap) {
        std::swap(e1, e2);
        std::swap(lo1, lo2);
        std::swap(hi1, hi2);
    }
    // Coordinates along each axis are relative to the camera (at 0), so complete_away grows
    // the box away from it.
    if (options.truncation_xz) {
        // The border's ray and its normal pointing away from the optical axis.
        const Eigen::Vector2d ray = frame
                                        .footprint(Eigen::Vector3d(options.truncation_xz->x(), 0.0,
                                                                   options.truncation_xz->y()))
                                        .normalized();
        Eigen::Vector2d outward(-ray.y(), ray.x());
        if (options.truncation_side != 0) {
            // Towards the hidden side: a point beside the cut, left or right of it in the image.
            const Eigen::Vector2d cut = *options.truncation_xz;
            const Eigen::Vector2d beside =
                cut +
                options.truncation_side * 0.1 * Eigen::Vector2d(cut.y(), -cut.x()).normalized();
            const Eigen::Vector2d towards =
                frame.footprint(Eigen::Vector3d(beside.x(), 0.0, beside.y())) -
                frame.footprint(Eigen::Vector3d(cut.x(), 0.0, cut.y()));
            if (outward.dot(towards) < 0.0) outward = -outward;
        } else if (outward.dot(frame.footprint(Eigen::Vector3d(0.0, 0.0, 1.0))) > 0.0) {
            outward = -outward;
        }
        if (options.prior_L_m > 0.0) {
            complete_cut(lo1, hi1, options.prior_L_m, e1, lo2, hi2, e2, outward,
                         options.truncation_side != 0);
        }
        if (options.prior_W_m > 0.0) {
            complete_cut(lo2, hi2, options.prior_W_m, e2, lo1, hi1, e1, outward,
                         options.truncation_side != 0);
        }
    } else {
        if (options.prior_L_m > 0.0) complete_away(lo1, hi1, options.prior_L_m);
        if (options.prior_W_m > 0.0) complete_away(lo2, hi2, options.prior_W_m);
    }

    double top = x.top_seen;
    const double bottom = has_ground && options.rest_on_ground ? 0.0 : x.bottom_seen;
    if (top - bottom < options.min_extent_m) top = bottom + options.min_extent_m;

    OrientedBox box;
    box.L_m = std::max(hi1 - lo1, options.min_extent_m);
    box.W_m = std::max(hi2 - lo2, options.min_extent_m);
    box.H_m = top - bottom;
    const Eigen::Vector2d centre_ab = ((lo1 + hi1) / 2.0) * e1 + ((lo2 + hi2) / 2.0) * e2;
    box.centre_m = frame.to_camera(centre_ab, (top + bottom) / 2.0);
    // Heading in camera coordinates, projected on the camera's x-z plane.
    const Eigen::Vector3d heading = e1.x() * frame.ex + e1.y() * frame.ez;
    box.theta = yaw_of(Eigen::Vector2d(heading.x(), heading.z()));
    return box;
}

/// The angle of the footprint's first axis in the ground frame: the imposed yaw, or the
/// L-shape search's, skipping axes along the ray of an image edge that cuts the points.
double footprint_angle(const GroundFrame& frame, const std::vector<Eigen::Vector2d>& ab,
                       const BoxFitOptions& options) {
    // The angle search costs 90 passes: run it on at most kMaxSearchPoints evenly strided points.
    constexpr std::size_t kMaxSearchPoints = 3000;
    double blocked = std::nan("");
    const double tolerance = options.truncation_exclusion_deg * kPi / 180.0;
    if (options.truncation_xz && options.truncation_side == 0) {
        // An image edge (not an occluder) lines the points up along its ray.
        const Eigen::Vector3d ray(options.truncation_xz->x(), 0.0, options.truncation_xz->y());
        blocked = std::atan2(frame.ez.dot(ray), frame.ex.dot(ray));
    }
    if (options.yaw_rad) {
        // Heading (cos t, -sin t) in camera x-z, expressed in the ground frame's axes.
        const Eigen::Vector3d heading(std::cos(*options.yaw_rad), 0.0, -std::sin(*options.yaw_rad));
        return std::atan2(frame.ez.dot(heading), frame.ex.dot(heading));
    }
    if (ab.size() > kMaxSearchPoints) {
        return best_gridded_lshape_angle(ab, options.angle_step_deg, blocked, tolerance);
    }
    return best_lshape_angle(ab, options.angle_step_deg, blocked, tolerance);
}

/// The cap on the ranges that weigh points over seen surface (see fit_extents), metres.
double seen_surface_cap_m(const std::vector<Eigen::Vector2d>& ab, const BoxFitOptions& options) {
    std::vector<double> range;
    range.reserve(ab.size());
    for (const auto& p : ab) range.push_back(p.norm());
    double cap_m =
        quantile(range, options.trim_fraction) + std::max(options.prior_L_m, options.prior_W_m);
    if (options.disparity_fb_px_m > 0.0) {
        cap_m = std::min(
            cap_m, std::sqrt(kAlongRaySmearShare * options.prior_L_m * options.disparity_fb_px_m));
    }
    return cap_m;
}

/// Extents of the footprint points `ab` along the axes e1, e2 and of their heights (trimmed
/// quantiles; the heights are reordered).
Extents fit_extents(const std::vector<Eigen::Vector2d>& ab, std::vector<double>& heights,
                    const Eigen::Vector2d& e1, const Eigen::Vector2d& e2,
                    const BoxFitOptions& options) {
    // Coordinates along the axes, each standing for one point or, over seen surface, for its
    // squared range (the surface a pixel spans there). Ranges are capped: a side runs at most
    // the prior's length behind the thing's near end (range smear and the next thing of a row
    // beyond weigh no more than a point there), and where one pixel of disparity moves a point
    // along the ray by more than a tenth of the prior's length, smear, not the pixels' spacing,
    // shapes the far end (the range at which long_face_angle's face rule stops trusting faces
    // along the ray).
    const double cap_m = options.area_weighted_extents ? seen_surface_cap_m(ab, options) : 0.0;
    // The points' coordinates along the axes: plain, or with weights over seen surface.
    std::vector<double> c1, c2;
    WeightedValues w1, w2;
    if (options.area_weighted_extents) {
        w1.reserve(ab.size());
        w2.reserve(ab.size());
    } else {
        c1.reserve(ab.size());
        c2.reserve(ab.size());
    }
    for (const auto& p : ab) {
        if (options.area_weighted_extents) {
            const double r = std::min(p.norm(), cap_m);
            const auto w = static_cast<float>(std::max(r * r, 1e-6));
            w1.emplace_back(p.dot(e1), w);
            w2.emplace_back(p.dot(e2), w);
        } else {
            c1.push_back(p.dot(e1));
            c2.push_back(p.dot(e2));
        }
    }
    // Quantiles along an axis: over seen surface when weighted, else over points (the linear
    // selection). Either reorders its values.
    const auto extent = [](std::vector<double>& c, WeightedValues& w, double q_lo, double q_hi) {
        return w.empty() ? quantiles(c, q_lo, q_hi) : weighted_quantiles(w, q_lo, q_hi);
    };
    const double t = options.trim_fraction;
    auto [lo1, hi1] = extent(c1, w1, t, 1.0 - t);
    auto [lo2, hi2] = extent(c2, w2, t, 1.0 - t);
    if (options.near_trim_fraction > t) {
        // The end nearer the camera (coordinates are relative to it) of an axis along the
        // viewing ray: trimmed further, as the near face's points are spread in front of it.
        const Eigen::Vector2d ray =
            (((lo1 + hi1) / 2.0) * e1 + ((lo2 + hi2) / 2.0) * e2).normalized();
        const auto trim_near = [&](std::vector<double>& c, WeightedValues& w, double& lo,
                                   double& hi, const Eigen::Vector2d& e) {
            if (std::abs(ray.dot(e)) < std::sqrt(0.5)) return;
            if (lo + hi >= 0.0) {
                lo = extent(c, w, options.near_trim_fraction, 1.0 - t).first;
            } else {
                hi = extent(c, w, t, 1.0 - options.near_trim_fraction).second;
            }
        };
        trim_near(c1, w1, lo1, hi1, e1);
        trim_near(c2, w2, lo2, hi2, e2);
    }

    const auto [bottom_seen, top_seen] = quantiles(heights, t, 1.0 - t);
    return {lo1, hi1, lo2, hi2, bottom_seen, top_seen};
}

}  // namespace

void BoxFitOptions::validate() const {
    if (prior_L_m < 0.0) throw std::invalid_argument("box.prior_L_m: must be >= 0");
    if (prior_W_m < 0.0) throw std::invalid_argument("box.prior_W_m: must be >= 0");
    if (prior_H_m < 0.0) throw std::invalid_argument("box.prior_H_m: must be >= 0");
    if (!(angle_step_deg > 0.0 && angle_step_deg <= 10.0)) {
        throw std::invalid_argument("box.angle_step_deg: must be in (0, 10]");
    }
    if (!(min_extent_m > 0.0)) throw std::invalid_argument("box.min_extent_m: must be > 0");
    if (!(trim_fraction >= 0.0 && trim_fraction < 0.2)) {
        throw std::invalid_argument("box.trim_fraction: must be in [0, 0.2)");
    }
    if (!(near_trim_fraction >= trim_fraction && near_trim_fraction < 0.2)) {
        throw std::invalid_argument("box.near_trim_fraction: must be in [trim_fraction, 0.2)");
    }
    if (!(face_tolerance_m > 0.0)) throw std::invalid_argument("box.face_tolerance_m: must be > 0");
    if (!(disparity_fb_px_m >= 0.0 && disparity_fb_px_m < 1e9)) {
        throw std::invalid_argument("box.disparity_fb_px_m: must be >= 0");
    }
    if (!(face_share >= 0.0 && face_share <= 1.0)) {
        throw std::invalid_argument("box.face_share: must be in [0, 1]");
    }
    if (yaw_rad && !std::isfinite(*yaw_rad)) {
        throw std::invalid_argument("box.yaw_rad: must be finite");
    }
    if (truncation_xz && !(truncation_xz->allFinite() && truncation_xz->norm() > 0.0)) {
        throw std::invalid_argument("box.truncation_xz: must be finite, not the camera's foot");
    }
    if (truncation_side < -1 || truncation_side > 1) {
        throw std::invalid_argument("box.truncation_side: must be -1, 0 or 1");
    }
    if (!(truncation_exclusion_deg >= 0.0 && truncation_exclusion_deg < 45.0)) {
        throw std::invalid_argument("box.truncation_exclusion_deg: must be in [0, 45)");
    }
}

namespace {

/// fit_upright_box on `given`'s axis, or on the one it searches (written to `chosen`).
OrientedBox fit_on_axis(const std::vector<Eigen::Vector3f>& points_m,
                        const std::optional<GroundPlane>& ground, const BoxFitOptions& options,
                        const FootprintAxis* given, FootprintAxis* chosen) {
    options.validate();
    if (points_m.empty()) throw std::invalid_argument("fit_upright_box: no points");
    const GroundFrame frame(ground);
    std::vector<Eigen::Vector2d> ab;
    std::vector<double> heights;
    ab.reserve(points_m.size());
    heights.reserve(points_m.size());
    for (const auto& p : points_m) {
        const Eigen::Vector3d q = p.cast<double>();
        ab.push_back(frame.footprint(q));
        heights.push_back(frame.height(q));
    }
    FootprintAxis axis = given ? *given : FootprintAxis{};
    if (!given) {
        axis.angle_rad = footprint_angle(frame, ab, options);
        // A straight face across the viewing ray (over 45 degrees from it) holding most points,
        // longer than a width, is a long side, its extent from pixel columns (along the ray a
        // face is no evidence: range smear itself lines points up along rays).
        if (const std::optional<double> face = long_face_angle(ab, options)) {
            axis.angle_rad = *face;
            axis.face_is_length = true;
        }
    }
    if (chosen) *chosen = axis;
    const Eigen::Vector2d e1(std::cos(axis.angle_rad), std::sin(axis.angle_rad));
    const Eigen::Vector2d e2(-std::sin(axis.angle_rad), std::cos(axis.angle_rad));
    return assemble_box(frame, ground.has_value(), options, axis.face_is_length, e1, e2,
                        fit_extents(ab, heights, e1, e2, options));
}

}  // namespace

OrientedBox fit_upright_box(const std::vector<Eigen::Vector3f>& points_m,
                            const std::optional<GroundPlane>& ground, const BoxFitOptions& options,
                            FootprintAxis& axis) {
    return fit_on_axis(points_m, ground, options, nullptr, &axis);
}

OrientedBox fit_upright_box(const std::vector<Eigen::Vector3f>& points_m,
                            const std::optional<GroundPlane>& ground,
                            const BoxFitOptions& options) {
    return fit_on_axis(points_m, ground, options, nullptr, nullptr);
}

OrientedBox fit_upright_box_on_axis(const std::vector<Eigen::Vector3f>& points_m,
                                    const std::optional<GroundPlane>& ground,
                                    const BoxFitOptions& options, const FootprintAxis& axis) {
    return fit_on_axis(points_m, ground, options, &axis, nullptr);
}

OrientedBox with_length(const OrientedBox& box, double length_m, bool keep_far_end) {
    const Eigen::Vector2d heading(std::cos(box.theta), -std::sin(box.theta));  // (x, z)
    const double far =
        heading.dot(Eigen::Vector2d(box.centre_m.x(), box.centre_m.z())) >= 0.0 ? 1.0 : -1.0;
    // The centre moves half the change, towards the end that moves.
    const double towards_far =
        keep_far_end ? -0.5 * (length_m - box.L_m) : 0.5 * (length_m - box.L_m);
    const Eigen::Vector2d shift = (far * towards_far) * heading;
    OrientedBox out = box;
    out.centre_m.x() += shift.x();
    out.centre_m.z() += shift.y();
    out.L_m = length_m;
    return out;
}

OrientedBox far_end_to_columns(const OrientedBox& box, const std::vector<Eigen::Vector3f>& points_m,
                               double max_length_m,
                               const std::optional<std::array<bool, 2>>& own_outline) {
    constexpr std::size_t kMinPoints = 20;
    // At a grazing angle a the side's position error moves the far end by that error / tan a:
    // at 10 degrees, 5.7 times (5 cm of stereo error across the side, 0.3 m along it).
    constexpr double kMinGrazingSin = 0.1736;  // sin 10 degrees
    // A car's side lies at most this far inside its widest point where it rounds into its
    // ends; outermost points farther in are range smear or another surface, not the side.
    constexpr double kMaxTaperM = 0.2;
    const std::array<bool, 2> may_shorten = own_outline.value_or(std::array<bool, 2>{false, false});
    const bool shorten = may_shorten[0] || may_shorten[1];
    if (points_m.size() < kMinPoints || (!shorten && !(max_length_m > box.L_m))) return box;
    const Eigen::Vector2d c(box.centre_m.x(), box.centre_m.z());
    if (c.norm() < 1e-6) return box;
    const Eigen::Vector2d e1(std::cos(box.theta), -std::sin(box.theta));  // heading, (x, z)
    const Eigen::Vector2d e2(std::sin(box.theta), std::cos(box.theta));
    const double along_ray = e1.dot(c.normalized());
    if (std::abs(along_ray) < std::sqrt(0.5)) return box;
    const double far = along_ray > 0.0 ? 1.0 : -1.0;        // the far end's direction along e1
    std::vector<std::pair<double, Eigen::Vector2d>> slope;  // a point's x / z, and the point
    std::vector<double> along;                              // points' coordinates, far way
    slope.reserve(points_m.size());
    along.reserve(points_m.size());
    for (const auto& p : points_m) {
        if (!(p.z() > 0.0f)) continue;
        const Eigen::Vector2d q(p.x(), p.z());
        slope.emplace_back(double{p.x()} / double{p.z()}, q);
        along.push_back(far * (q - c).dot(e1));
    }
    if (slope.size() < kMinPoints) return box;
    const std::size_t k = std::max<std::size_t>(10, slope.size() / 500);
    const double farthest = *std::max_element(along.begin(), along.end());
    // A far end moved inwards keeps the k outermost points along the length behind it.
    std::nth_element(along.begin(), along.end() - 1 - static_cast<std::ptrdiff_t>(k), along.end());
    const double floor = *(along.end() - 1 - static_cast<std::ptrdiff_t>(k));
    const auto by_slope = [](const auto& a, const auto& b) { return a.first < b.first; };
    // The long side facing the camera, as an offset from the centre along e2.
    const double fitted = (e2.dot(c) > 0.0 ? -0.5 : 0.5) * box.W_m;
    double best = -std::numeric_limits<double>::infinity();
    bool best_may_shorten = false;
    for (const int side : {0, 1}) {
        // The k + 1 outermost points on one side of the image (0: left, the lowest x / z), the
        // outermost ray the last.
        const auto nth = side == 0 ? slope.begin() + static_cast<std::ptrdiff_t>(k)
                                   : slope.end() - 1 - static_cast<std::ptrdiff_t>(k);
        std::nth_element(slope.begin(), nth, slope.end(), by_slope);
        const Eigen::Vector2d ray = Eigen::Vector2d(nth->first, 1.0).normalized();
        const double cross = ray.x() * e1.y() - ray.y() * e1.x();
        if (std::abs(cross) < kMinGrazingSin) continue;
        // The side line: the box's side, or, when the outline is the thing's own, where those
        // points stand if within a taper of it.
        Eigen::Vector2d line = c + fitted * e2;
        if (own_outline) {
            std::vector<double> offset;
            const auto first = side == 0 ? slope.begin() : nth;
            const auto last = side == 0 ? nth + 1 : slope.end();
            for (auto it = first; it != last; ++it) offset.push_back((it->second - c).dot(e2));
            const auto mid = offset.begin() + static_cast<std::ptrdiff_t>(offset.size() / 2);
            std::nth_element(offset.begin(), mid, offset.end());
            if (std::abs(*mid - fitted) <= kMaxTaperM) line = c + *mid * e2;
        }
        // line + a e1 on the ray: (line + a e1) x ray = 0, and cross = ray x e1.
        const double a = far * (line.x() * ray.y() - line.y() * ray.x()) / cross;
        if (a > best) {
            best = a;
            best_may_shorten = may_shorten[static_cast<std::size_t>(side)];
        }
    }
    if (!std::isfinite(best)) return box;
    double reach = std::min(best, farthest) - 0.5 * box.L_m;
    if (reach < 0.0)
        reach = best_may_shorten ? std::min(0.0, std::max(reach, floor - 0.5 * box.L_m)) : 0.0;
    if (reach == 0.0) return box;
    return with_length(box, std::clamp(box.L_m + reach, 0.0, std::max(max_length_m, box.L_m)),
                       false);
}

OrientedBox fit_upright_box_weighted(const std::vector<Eigen::Vector3f>& points_m,
                                     const std::vector<float>& weights,
                                     const std::optional<GroundPlane>& ground,
                                     const BoxFitOptions& options) {
    options.validate();
    if (points_m.empty()) throw std::invalid_argument("fit_upright_box_weighted: no points");
    if (weights.size() != points_m.size()) {
        throw std::invalid_argument("fit_upright_box_weighted: weights and points differ in size");
    }
    for (float w : weights) {
        if (!(w > 0.0f && std::isfinite(w))) {
            throw std::invalid_argument("fit_upright_box_weighted: weights must be > 0");
        }
    }
    const GroundFrame frame(ground);
    std::vector<Eigen::Vector2d> ab;
    WeightedValues heights;
    ab.reserve(points_m.size());
    heights.reserve(points_m.size());
    for (std::size_t i = 0; i < points_m.size(); ++i) {
        const Eigen::Vector3d q = points_m[i].cast<double>();
        ab.push_back(frame.footprint(q));
        heights.emplace_back(frame.height(q), weights[i]);
    }
    double angle = 0.0;
    if (options.yaw_rad) {
        const Eigen::Vector3d heading(std::cos(*options.yaw_rad), 0.0, -std::sin(*options.yaw_rad));
        angle = std::atan2(frame.ez.dot(heading), frame.ex.dot(heading));
    } else {
        angle = best_weighted_lshape_angle(ab, weights, options.angle_step_deg);
    }
    const Eigen::Vector2d e1(std::cos(angle), std::sin(angle));
    const Eigen::Vector2d e2(-std::sin(angle), std::cos(angle));
    WeightedValues c1, c2;
    c1.reserve(ab.size());
    c2.reserve(ab.size());
    for (std::size_t i = 0; i < ab.size(); ++i) {
        c1.emplace_back(ab[i].dot(e1), weights[i]);
        c2.emplace_back(ab[i].dot(e2), weights[i]);
    }
    const double t = options.trim_fraction;
    const auto [lo1, hi1] = weighted_quantiles(c1, t, 1.0 - t);
    const auto [lo2, hi2] = weighted_quantiles(c2, t, 1.0 - t);
    const auto [bottom_seen, top_seen] = weighted_quantiles(heights, t, 1.0 - t);
    return assemble_box(frame, ground.has_value(), options, false, e1, e2,
                        {lo1, hi1, lo2, hi2, bottom_seen, top_seen});
}

}  // namespace cloud_analysis
