#include "cloud_analysis/entities/boxes.hpp"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <limits>
#include <stdexcept>
#include <utility>

#include <Eigen/Eigenvalues>
#include <Eigen/Geometry>

#include "cloud_analysis/support/select.hpp"
#include "stereoscene/support/angles.hpp"

namespace cloud_analysis {
namespace {

using stereoscene::support::kPi;
/// A straight face longer than this many prior widths cannot be a thing's front or rear.
constexpr double kFaceWidths = 1.2;
/// A face along the viewing ray counts when a pixel of disparity moves its far end by at most
/// this share of its length.
constexpr double kAlongRaySmearShare = 0.1;
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

/// Lanes of the closeness score's sums: point i adds to lane i % kLanes, and the lanes are
/// added in a fixed order, so that the score is the same float whatever the instruction set.
constexpr std::size_t kLanes = 8;

/// Zhang et al.'s closeness score of the rectangle with axes (ca, sa) and (-sa, ca) around
/// points (x[i], y[i]): the sum of w[i] / max(distance to the nearest edge, 0.01), w = 1 when
/// null; c1 and c2 (n each) receive the coordinates along the axes. Also compiled for AVX2,
/// chosen at load time: the same operations in the same lanes, so the same score, eight
/// floats at a time instead of four.
__attribute__((target_clones("avx2", "default"))) float closeness_score(
    const float* __restrict x, const float* __restrict y, const float* __restrict w, std::size_t n,
    float ca, float sa, float* __restrict c1, float* __restrict c2) {
    constexpr float kInf = std::numeric_limits<float>::infinity();
    float min1[kLanes], max1[kLanes], min2[kLanes], max2[kLanes];
    for (std::size_t j = 0; j < kLanes; ++j) {
        min1[j] = kInf;
        max1[j] = -kInf;
        min2[j] = kInf;
        max2[j] = -kInf;
    }
    const std::size_t blocks = n / kLanes * kLanes;
    const auto extend = [&](std::size_t i, std::size_t j) {
        const float a = x[i] * ca + y[i] * sa;
        const float b = y[i] * ca - x[i] * sa;
        c1[i] = a;
        c2[i] = b;
        min1[j] = a < min1[j] ? a : min1[j];
        max1[j] = a > max1[j] ? a : max1[j];
        min2[j] = b < min2[j] ? b : min2[j];
        max2[j] = b > max2[j] ? b : max2[j];
    };
    for (std::size_t i = 0; i < blocks; i += kLanes) {
        for (std::size_t j = 0; j < kLanes; ++j) extend(i + j, j);
    }
    for (std::size_t i = blocks; i < n; ++i) extend(i, i - blocks);
    float lo1 = kInf, hi1 = -kInf, lo2 = kInf, hi2 = -kInf;
    for (std::size_t j = 0; j < kLanes; ++j) {
        lo1 = std::min(lo1, min1[j]);
        hi1 = std::max(hi1, max1[j]);
        lo2 = std::min(lo2, min2[j]);
        hi2 = std::max(hi2, max2[j]);
    }
    // w / (distance to the nearest edge, at least 0.01), kLanes points at a time as one GCC
    // vector (two SSE registers by default, one AVX2 register in that clone), the rest one by
    // one into the same lanes.
    using Lanes = float __attribute__((vector_size(kLanes * sizeof(float))));
    Lanes sums = {};
    const Lanes floor = Lanes{} + 0.01f;
    for (std::size_t i = 0; i < blocks; i += kLanes) {
        Lanes u1, u2, weight;
        std::memcpy(&u1, c1 + i, sizeof u1);
        std::memcpy(&u2, c2 + i, sizeof u2);
        const Lanes a1 = hi1 - u1, b1 = u1 - lo1, a2 = hi2 - u2, b2 = u2 - lo2;
        const Lanes d1 = a1 < b1 ? a1 : b1;
        const Lanes d2 = a2 < b2 ? a2 : b2;
        const Lanes d = d1 < d2 ? d1 : d2;
        const Lanes closeness = 1.0f / (d > floor ? d : floor);
        if (w != nullptr) {
            std::memcpy(&weight, w + i, sizeof weight);
            sums += weight * closeness;
        } else {
            sums += closeness;
        }
    }
    float sum[kLanes];
    std::memcpy(sum, &sums, sizeof sum);
    for (std::size_t i = blocks; i < n; ++i) {
        const float a1 = hi1 - c1[i], b1 = c1[i] - lo1, a2 = hi2 - c2[i], b2 = c2[i] - lo2;
        const float d1 = a1 < b1 ? a1 : b1;
        const float d2 = a2 < b2 ? a2 : b2;
        const float d = d1 < d2 ? d1 : d2;
        const float closeness = 1.0f / (d > 0.01f ? d : 0.01f);
        sum[i - blocks] += w != nullptr ? w[i] * closeness : closeness;
    }
    float total = 0.0f;
    for (std::size_t j = 0; j < kLanes; ++j) total += sum[j];
    return total;
}

/// Points relative to their mean, as floats (which keeps micrometres) for closeness_score.
struct CentredPoints {
    std::vector<float> x, y, c1, c2;
    explicit CentredPoints(const std::vector<Eigen::Vector2d>& pts)
        : x(pts.size()), y(pts.size()), c1(pts.size()), c2(pts.size()) {
        Eigen::Vector2d mean = Eigen::Vector2d::Zero();
        for (const auto& p : pts) mean += p;
        mean /= static_cast<double>(std::max<std::size_t>(pts.size(), 1));
        for (std::size_t i = 0; i < pts.size(); ++i) {
            x[i] = static_cast<float>(pts[i].x() - mean.x());
            y[i] = static_cast<float>(pts[i].y() - mean.y());
        }
    }
    float score(double a, const float* w) {
        return closeness_score(x.data(), y.data(), w, x.size(), static_cast<float>(std::cos(a)),
                               static_cast<float>(std::sin(a)), c1.data(), c2.data());
    }
};

/// Whether rectangle axis angle `a` lies within `tolerance` of `blocked` modulo 90 degrees
/// (never when blocked is NaN: nothing blocked).
bool blocked_angle(double a, double blocked, double tolerance) {
    if (std::isnan(blocked)) return false;
    double d = std::fmod(std::abs(a - blocked), kPi / 2.0);
    return std::min(d, kPi / 2.0 - d) < tolerance;
}

/// Angle in [0, pi/2) of the first rectangle axis maximising Zhang et al.'s closeness score,
/// skipping axes within `tolerance` of `blocked` (modulo 90 degrees; NaN: none).
double best_lshape_angle(const std::vector<Eigen::Vector2d>& pts, double step_deg,
                         double blocked = std::nan(""), double tolerance = 0.0) {
    const int steps = std::max(1, static_cast<int>(std::lround(90.0 / step_deg)));
    CentredPoints centred(pts);
    double best_angle = 0.0;
    float best_score = -1.0f;
    for (int s = 0; s < steps; ++s) {
        const double a = s * (kPi / 2.0) / steps;
        if (blocked_angle(a, blocked, tolerance)) continue;
        const float score = centred.score(a, nullptr);
        if (score > best_score) {
            best_score = score;
            best_angle = a;
        }
    }
    return best_angle;
}

/// As best_lshape_angle for weighted points (each point's closeness term times its weight),
/// searched coarse to fine: kCoarseStepDeg steps over 90 degrees, then step_deg steps within
/// one coarse step of the best (29 passes instead of 90 at 1 degree).
double best_weighted_lshape_angle(const std::vector<Eigen::Vector2d>& pts,
                                  const std::vector<float>& weights, double step_deg,
                                  double blocked = std::nan(""), double tolerance = 0.0) {
    constexpr double kCoarseStepDeg = 5.0;
    CentredPoints centred(pts);
    const double coarse = kCoarseStepDeg * kPi / 180.0;
    double best_angle = 0.0;
    float best_score = -1.0f;
    const auto consider = [&](double a) {
        if (blocked_angle(a, blocked, tolerance)) return;
        const float s = centred.score(a, weights.data());
        if (s > best_score) {
            best_score = s;
            best_angle = a;
        }
    };
    for (int k = 0; k < static_cast<int>(std::lround(90.0 / kCoarseStepDeg)); ++k) {
        consider(k * coarse);
    }
    const double centre = best_angle;
    const double step = std::min(step_deg, kCoarseStepDeg) * kPi / 180.0;
    const int reach =
        static_cast<int>(std::lround(kCoarseStepDeg / std::min(step_deg, kCoarseStepDeg)));
    for (int k = -reach; k <= reach; ++k) {
        if (k != 0) consider(centre + k * step);
    }
    // The score repeats every 90 degrees: wrap into [0, pi/2).
    double a = std::fmod(best_angle, kPi / 2.0);
    if (a < 0.0) a += kPi / 2.0;
    return a;
}

/// A straight face of points: unit direction, share of the points within the tolerance of
/// it, and its length (2-98 % extent of those points along it).
struct Face {
    Eigen::Vector2d direction;
    Eigen::Vector2d centre;  ///< mean of the points on it
    double share = 0.0;
    double length_m = 0.0;
};

/// The line through the most points (deterministic RANSAC over point pairs, counted on at
/// most kFaceSample strided points), refined by the principal axis of its inliers.
std::optional<Face> dominant_face(const std::vector<Eigen::Vector2d>& pts, double tolerance_m) {
    constexpr std::size_t kFaceSample = 400;
    constexpr std::size_t kHypotheses = 64;
    if (pts.size() < 10) return std::nullopt;
    const std::size_t stride = pts.size() / kFaceSample + 1;
    // The strided sample as two coordinate arrays, so that each hypothesis' count is one
    // vectorised loop (the same operations as normal.dot(p - q) point by point).
    std::vector<double> sx, sy;
    for (std::size_t m = 0; m < pts.size(); m += stride) {
        sx.push_back(pts[m].x());
        sy.push_back(pts[m].y());
    }
    std::size_t best_count = 0;
    Eigen::Vector2d best_point, best_normal;
    for (std::size_t k = 0; k < kHypotheses; ++k) {
        const std::size_t i = (k * 2654435761u) % pts.size();
        const std::size_t j = (i + pts.size() / 2 + k * 40503u) % pts.size();
        const Eigen::Vector2d d = pts[j] - pts[i];
        if (d.norm() < 0.3) continue;
        const Eigen::Vector2d normal(-d.y() / d.norm(), d.x() / d.norm());
        const double nx = normal.x(), ny = normal.y(), qx = pts[i].x(), qy = pts[i].y();
        std::size_t count = 0;
        for (std::size_t m = 0; m < sx.size(); ++m) {
            count += std::abs(nx * (sx[m] - qx) + ny * (sy[m] - qy)) <= tolerance_m ? 1 : 0;
        }
        if (count > best_count) {
            best_count = count;
            best_point = pts[i];
            best_normal = normal;
        }
    }
    if (best_count == 0) return std::nullopt;
    std::vector<Eigen::Vector2d> inliers;
    Eigen::Vector2d mean = Eigen::Vector2d::Zero();
    for (const auto& p : pts) {
        if (std::abs(best_normal.dot(p - best_point)) <= tolerance_m) {
            inliers.push_back(p);
            mean += p;
        }
    }
    mean /= static_cast<double>(inliers.size());
    Eigen::Matrix2d cov = Eigen::Matrix2d::Zero();
    for (const auto& p : inliers) cov += (p - mean) * (p - mean).transpose();
    const Eigen::SelfAdjointEigenSolver<Eigen::Matrix2d> eig(cov);
    Face face;
    face.direction = eig.eigenvectors().col(1);
    face.centre = mean;
    face.share = static_cast<double>(inliers.size()) / static_cast<double>(pts.size());
    std::vector<double> along;
    along.reserve(inliers.size());
    for (const auto& p : inliers) along.push_back(face.direction.dot(p));
    const auto [lo, hi] = quantiles(along, 0.02, 0.98);
    face.length_m = hi - lo;
    return face;
}

/// KITTI yaw of a heading given in ground (x, z) coordinates, front/back resolved to z >= 0.
double yaw_of(Eigen::Vector2d heading_xz) {
    if (heading_xz.y() < 0.0 || (heading_xz.y() == 0.0 && heading_xz.x() < 0.0)) {
        heading_xz = -heading_xz;
    }
    return std::atan2(-heading_xz.y(), heading_xz.x());
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
            swap = options.short_face_is_end && !options.truncation_xz
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
        if (outward.dot(frame.footprint(Eigen::Vector3d(0.0, 0.0, 1.0))) > 0.0) outward = -outward;
        if (options.prior_L_m > 0.0) {
            complete_at_edge(lo1, hi1, options.prior_L_m, e1, lo2, hi2, e2, outward);
        }
        if (options.prior_W_m > 0.0) {
            complete_at_edge(lo2, hi2, options.prior_W_m, e2, lo1, hi1, e1, outward);
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
    if (!(truncation_exclusion_deg >= 0.0 && truncation_exclusion_deg < 45.0)) {
        throw std::invalid_argument("box.truncation_exclusion_deg: must be in [0, 45)");
    }
}

double lshape_yaw(const std::vector<Eigen::Vector2d>& xz_m, double angle_step_deg) {
    if (xz_m.size() < 2) return 0.0;
    const double a = best_lshape_angle(xz_m, angle_step_deg);
    const Eigen::Vector2d e1(std::cos(a), std::sin(a));
    const Eigen::Vector2d e2(-std::sin(a), std::cos(a));
    double min1 = 1e300, max1 = -1e300, min2 = 1e300, max2 = -1e300;
    for (const auto& p : xz_m) {
        min1 = std::min(min1, p.dot(e1));
        max1 = std::max(max1, p.dot(e1));
        min2 = std::min(min2, p.dot(e2));
        max2 = std::max(max2, p.dot(e2));
    }
    return yaw_of(max1 - min1 >= max2 - min2 ? e1 : e2);
}

OrientedBox fit_upright_box(const std::vector<Eigen::Vector3f>& points_m,
                            const std::optional<GroundPlane>& ground,
                            const BoxFitOptions& options) {
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
    // The angle search costs 90 passes: run it on at most kMaxSearchPoints evenly strided points.
    constexpr std::size_t kMaxSearchPoints = 3000;
    double angle = 0.0;
    double blocked = std::nan("");
    const double tolerance = options.truncation_exclusion_deg * kPi / 180.0;
    if (options.truncation_xz) {
        const Eigen::Vector3d ray(options.truncation_xz->x(), 0.0, options.truncation_xz->y());
        blocked = std::atan2(frame.ez.dot(ray), frame.ex.dot(ray));
    }
    if (options.yaw_rad) {
        // Heading (cos t, -sin t) in camera x-z, expressed in the ground frame's axes.
        const Eigen::Vector3d heading(std::cos(*options.yaw_rad), 0.0, -std::sin(*options.yaw_rad));
        angle = std::atan2(frame.ez.dot(heading), frame.ex.dot(heading));
    } else if (ab.size() > kMaxSearchPoints) {
        // Points above one another share a footprint position: count them on a fine grid over
        // the cluster's footprint and search with the counts as weights, which scores like
        // every point at a fraction of the cost and whatever their order (a strided sample
        // scored differently and moved headings by degrees).
        Eigen::Vector2d lo = ab.front(), hi = ab.front();
        for (const auto& p : ab) {
            lo = lo.cwiseMin(p);
            hi = hi.cwiseMax(p);
        }
        double cell = 0.02;
        const auto cells_along = [&](double extent) {
            return static_cast<std::size_t>(extent / cell) + 1;
        };
        while (cells_along(hi.x() - lo.x()) * cells_along(hi.y() - lo.y()) > (1u << 20)) {
            cell *= 2.0;
        }
        const std::size_t na = cells_along(hi.x() - lo.x());
        const std::size_t nb = cells_along(hi.y() - lo.y());
        // Counted per cell, then the occupied cells numbered in cell order and summed there:
        // 4 bytes per grid cell instead of a count and a sum for each. The occupied cells are
        // listed as they fill and sorted, not found by scanning the grid (smear can stretch
        // the footprint over 10^5 cells for a few thousand points).
        std::vector<std::uint32_t> slot(na * nb, 0);
        std::vector<std::uint32_t> cell_of(ab.size());
        std::vector<std::uint32_t> occupied;
        for (std::size_t i = 0; i < ab.size(); ++i) {
            const auto a = std::min(na - 1, static_cast<std::size_t>((ab[i].x() - lo.x()) / cell));
            const auto b = std::min(nb - 1, static_cast<std::size_t>((ab[i].y() - lo.y()) / cell));
            cell_of[i] = static_cast<std::uint32_t>(a * nb + b);
            if (slot[a * nb + b]++ == 0) occupied.push_back(cell_of[i]);
        }
        std::sort(occupied.begin(), occupied.end());
        std::vector<float> counts(occupied.size());
        for (std::size_t k = 0; k < occupied.size(); ++k) {
            counts[k] = static_cast<float>(slot[occupied[k]]);
            slot[occupied[k]] = static_cast<std::uint32_t>(k);
        }
        std::vector<Eigen::Vector2d> cells(counts.size(), Eigen::Vector2d::Zero());
        for (std::size_t i = 0; i < ab.size(); ++i) cells[slot[cell_of[i]]] += ab[i];
        for (std::size_t k = 0; k < cells.size(); ++k) {
            cells[k] /= static_cast<double>(counts[k]);
        }
        angle =
            best_weighted_lshape_angle(cells, counts, options.angle_step_deg, blocked, tolerance);
    } else {
        angle = best_lshape_angle(ab, options.angle_step_deg, blocked, tolerance);
    }
    // A straight face across the viewing ray (more than 45 degrees from it) holding most of the
    // points and longer than a width is a long side: its extent comes from pixel columns, and
    // at range the closeness criterion follows the smear and stray points around it instead.
    // (Along the ray a face is no evidence: range smear itself lines points up along rays.)
    bool face_is_length = false;
    if (!options.yaw_rad && options.face_share > 0.0 && options.prior_W_m > 0.0 &&
        options.prior_L_m > kFaceWidths * options.prior_W_m) {
        const auto face = dominant_face(ab, options.face_tolerance_m);
        const auto sharp = [&](const Face& f) {
            if (std::abs(f.direction.dot(f.centre.normalized())) < std::sqrt(0.5)) return true;
            // Along the ray: a face only where a pixel of disparity error moves its far end by
            // at most a tenth of its length and of the thing's prior length (a long row's side
            // at 20 m is no one thing's face).
            const double far = f.centre.norm() + f.length_m / 2.0;
            return options.disparity_fb_px_m > 0.0 &&
                   far * far / options.disparity_fb_px_m <=
                       kAlongRaySmearShare * std::min(f.length_m, options.prior_L_m);
        };
        if (face && face->share >= options.face_share &&
            face->length_m >= kFaceWidths * options.prior_W_m && sharp(*face)) {
            angle = std::atan2(face->direction.y(), face->direction.x());
            face_is_length = true;
        }
    }
    Eigen::Vector2d e1(std::cos(angle), std::sin(angle));
    Eigen::Vector2d e2(-std::sin(angle), std::cos(angle));
    // Coordinates along the axes, each standing for one point or, over seen surface, for its
    // squared range (the surface a pixel spans there). Ranges are capped: a side runs at most
    // the prior's length behind the thing's near end (range smear and the next thing of a row
    // beyond weigh no more than a point there), and where one pixel of disparity moves a point
    // along the ray by more than a tenth of the prior's length, smear, not the pixels' spacing,
    // shapes the far end (the range at which the face rule above stops trusting faces along the
    // ray).
    double cap_m = 0.0;
    if (options.area_weighted_extents) {
        std::vector<double> range;
        range.reserve(ab.size());
        for (const auto& p : ab) range.push_back(p.norm());
        cap_m =
            quantile(range, options.trim_fraction) + std::max(options.prior_L_m, options.prior_W_m);
        if (options.disparity_fb_px_m > 0.0) {
            cap_m = std::min(cap_m, std::sqrt(kAlongRaySmearShare * options.prior_L_m *
                                              options.disparity_fb_px_m));
        }
    }
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
    return assemble_box(frame, ground.has_value(), options, face_is_length, e1, e2,
                        {lo1, hi1, lo2, hi2, bottom_seen, top_seen});
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

OrientedBox extend_far_end_to_columns(const OrientedBox& box,
                                      const std::vector<Eigen::Vector3f>& points_m,
                                      double max_length_m) {
    constexpr std::size_t kMinPoints = 20;
    // At a grazing angle a the side's position error moves the far end by that error / tan a:
    // at 10 degrees, 5.7 times (5 cm of stereo error across the side, 0.3 m along it).
    constexpr double kMinGrazingSin = 0.1736;  // sin 10 degrees
    if (points_m.size() < kMinPoints || !(max_length_m > box.L_m)) return box;
    const Eigen::Vector2d c(box.centre_m.x(), box.centre_m.z());
    if (c.norm() < 1e-6) return box;
    const Eigen::Vector2d e1(std::cos(box.theta), -std::sin(box.theta));  // heading, (x, z)
    const Eigen::Vector2d e2(std::sin(box.theta), std::cos(box.theta));
    const double along_ray = e1.dot(c.normalized());
    if (std::abs(along_ray) < std::sqrt(0.5)) return box;
    const double far = along_ray > 0.0 ? 1.0 : -1.0;  // the far end's direction along e1
    // The long side facing the camera: its outward normal points back at the camera.
    const Eigen::Vector2d side = c + (e2.dot(c) > 0.0 ? -0.5 : 0.5) * box.W_m * e2;
    std::vector<double> slope;
    slope.reserve(points_m.size());
    double farthest = -std::numeric_limits<double>::infinity();  // points' extent, far way
    for (const auto& p : points_m) {
        if (!(p.z() > 0.0f)) continue;
        slope.push_back(double{p.x()} / double{p.z()});
        farthest = std::max(farthest, far * (Eigen::Vector2d(p.x(), p.z()) - c).dot(e1));
    }
    if (slope.size() < kMinPoints) return box;
    const std::size_t k = std::max<std::size_t>(10, slope.size() / 500);
    double best = -std::numeric_limits<double>::infinity();
    for (const std::size_t rank : {k, slope.size() - 1 - k}) {
        std::nth_element(slope.begin(), slope.begin() + static_cast<std::ptrdiff_t>(rank),
                         slope.end());
        const Eigen::Vector2d ray = Eigen::Vector2d(slope[rank], 1.0).normalized();
        const double cross = ray.x() * e1.y() - ray.y() * e1.x();
        if (std::abs(cross) < kMinGrazingSin) continue;
        // side + a e1 on the ray: (side + a e1) x ray = 0, and cross = ray x e1.
        const double a = (side.x() * ray.y() - side.y() * ray.x()) / cross;
        best = std::max(best, far * a);
    }
    const double reach = std::min(best, farthest) - 0.5 * box.L_m;
    if (!(reach > 0.0)) return box;
    return with_length(box, std::min(box.L_m + reach, max_length_m), false);
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
