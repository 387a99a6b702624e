// The heading of a box's footprint: Zhang et al.'s L-shape closeness search over rectangle
// axes, and the straight face that is a long side.

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <limits>

#include <Eigen/Eigenvalues>

#include "boxes_internal.hpp"
#include "cloud_analysis/support/select.hpp"
#include "stereoscene/support/angles.hpp"

namespace cloud_analysis {
namespace {

using stereoscene::support::kPi;
/// A straight face longer than this many prior widths cannot be a thing's front or rear.
constexpr double kFaceWidths = 1.2;

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

}  // namespace

double yaw_of(Eigen::Vector2d heading_xz) {
    if (heading_xz.y() < 0.0 || (heading_xz.y() == 0.0 && heading_xz.x() < 0.0)) {
        heading_xz = -heading_xz;
    }
    return std::atan2(-heading_xz.y(), heading_xz.x());
}

double best_lshape_angle(const std::vector<Eigen::Vector2d>& pts, double step_deg, double blocked,
                         double tolerance) {
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

double best_weighted_lshape_angle(const std::vector<Eigen::Vector2d>& pts,
                                  const std::vector<float>& weights, double step_deg,
                                  double blocked, double tolerance) {
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

double best_gridded_lshape_angle(const std::vector<Eigen::Vector2d>& ab, double step_deg,
                                 double blocked, double tolerance) {
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
    return best_weighted_lshape_angle(cells, counts, step_deg, blocked, tolerance);
}

std::optional<double> long_face_angle(const std::vector<Eigen::Vector2d>& ab,
                                      const BoxFitOptions& options) {
    if (options.yaw_rad || !(options.face_share > 0.0 && options.prior_W_m > 0.0 &&
                             options.prior_L_m > kFaceWidths * options.prior_W_m)) {
        return std::nullopt;
    }
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
        return std::atan2(face->direction.y(), face->direction.x());
    }
    return std::nullopt;
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

}  // namespace cloud_analysis
