// The thesis's extractors: one axis-aligned box per class (theta 0) from the points' centre of
// mass, their mean offsets or their variance.

#include <algorithm>
#include <cmath>

#include "cloud_analysis/entities/boxes.hpp"

namespace cloud_analysis {
namespace {

Eigen::Vector3d mean_of(const std::vector<Eigen::Vector3f>& pts) {
    Eigen::Vector3d m = Eigen::Vector3d::Zero();
    for (const auto& p : pts) m += p.cast<double>();
    return pts.empty() ? m : Eigen::Vector3d(m / static_cast<double>(pts.size()));
}

/// Box with theta 0 from per-axis lower and upper bounds (x -> L, y -> H, z -> W).
OrientedBox axis_box(const Eigen::Vector3d& lo, const Eigen::Vector3d& hi) {
    OrientedBox box;
    box.centre_m = (lo + hi) / 2.0;
    box.theta = 0.0;
    box.L_m = std::max(hi.x() - lo.x(), 1e-3);
    box.H_m = std::max(hi.y() - lo.y(), 1e-3);
    box.W_m = std::max(hi.z() - lo.z(), 1e-3);
    return box;
}

}  // namespace

OrientedBox centroid_box(const std::vector<Eigen::Vector3f>& points_m,
                         const Eigen::Vector3d& size_LHW_m) {
    OrientedBox box;
    box.centre_m = mean_of(points_m);
    box.L_m = size_LHW_m.x();
    box.H_m = size_LHW_m.y();
    box.W_m = size_LHW_m.z();
    return box;
}

OrientedBox average_box(const std::vector<Eigen::Vector3f>& points_m) {
    const Eigen::Vector3d c = mean_of(points_m);
    Eigen::Vector3d sum_pos = Eigen::Vector3d::Zero(), sum_neg = Eigen::Vector3d::Zero();
    Eigen::Vector3d n_pos = Eigen::Vector3d::Zero(), n_neg = Eigen::Vector3d::Zero();
    for (const auto& p : points_m) {
        const Eigen::Vector3d o = p.cast<double>() - c;
        for (int k = 0; k < 3; ++k) {
            if (o[k] >= 0.0) {
                sum_pos[k] += o[k];
                n_pos[k] += 1.0;
            } else {
                sum_neg[k] -= o[k];
                n_neg[k] += 1.0;
            }
        }
    }
    Eigen::Vector3d lo = c, hi = c;
    for (int k = 0; k < 3; ++k) {
        if (n_pos[k] > 0.0) hi[k] += 2.0 * sum_pos[k] / n_pos[k];
        if (n_neg[k] > 0.0) lo[k] -= 2.0 * sum_neg[k] / n_neg[k];
    }
    return axis_box(lo, hi);
}

OrientedBox variance_box(const std::vector<Eigen::Vector3f>& points_m) {
    const Eigen::Vector3d c = mean_of(points_m);
    Eigen::Vector3d var = Eigen::Vector3d::Zero();
    for (const auto& p : points_m) var += (p.cast<double>() - c).cwiseAbs2();
    if (!points_m.empty()) var /= static_cast<double>(points_m.size());
    const Eigen::Vector3d half = std::sqrt(3.0) * var.cwiseSqrt();
    return axis_box(c - half, c + half);
}

}  // namespace cloud_analysis
