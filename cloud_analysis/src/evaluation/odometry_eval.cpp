#include "cloud_analysis/evaluation/odometry_eval.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include <Eigen/LU>
#include "stereoscene/support/angles.hpp"

namespace cloud_analysis {
namespace {

using stereoscene::support::kDegPerRad;

/// Rotation angle of a pose, radians (devkit rotationError).
double rotation_angle(const odometry::Pose& T) {
    const double c = 0.5 * (T(0, 0) + T(1, 1) + T(2, 2) - 1.0);
    return std::acos(std::clamp(c, -1.0, 1.0));
}

}  // namespace

std::vector<double> segment_lengths(double path_m) {
    std::vector<double> out;
    for (double L :
         {5.0, 10.0, 20.0, 50.0, 100.0, 200.0, 300.0, 400.0, 500.0, 600.0, 700.0, 800.0}) {
        if (L <= path_m) out.push_back(L);
    }
    return out;
}

OdometryErrors evaluate_odometry(const std::vector<odometry::Pose>& estimate,
                                 const std::vector<odometry::Pose>& truth) {
    if (estimate.size() != truth.size()) {
        throw std::invalid_argument(
            "the poses and the truth differ in frames: " + std::to_string(estimate.size()) +
            " and " + std::to_string(truth.size()));
    }
    if (truth.size() < 2) throw std::invalid_argument("fewer than two frames to score");
    OdometryErrors out;
    out.frames = truth.size();
    // Distance along the true path to each frame.
    std::vector<double> along(truth.size(), 0.0);
    for (std::size_t i = 1; i < truth.size(); ++i) {
        along[i] = along[i - 1] +
                   (truth[i].topRightCorner<3, 1>() - truth[i - 1].topRightCorner<3, 1>()).norm();
    }
    out.path_m = along.back();
    double t_sum = 0.0, r_sum = 0.0;
    std::size_t count = 0;
    for (const double L : segment_lengths(out.path_m)) {
        SegmentErrors s;
        s.length_m = L;
        for (std::size_t first = 0; first < truth.size(); ++first) {
            // The first frame at least L along the path from `first`.
            const auto last_it = std::lower_bound(
                along.begin() + static_cast<std::ptrdiff_t>(first), along.end(), along[first] + L);
            if (last_it == along.end()) break;
            const auto last = static_cast<std::size_t>(last_it - along.begin());
            const odometry::Pose delta_truth = truth[first].inverse() * truth[last];
            const odometry::Pose delta_est = estimate[first].inverse() * estimate[last];
            const odometry::Pose error = delta_est.inverse() * delta_truth;
            const double t = error.topRightCorner<3, 1>().norm() / L;
            const double r = rotation_angle(error) / L;
            s.translation_pct += 100.0 * t;
            s.rotation_deg_per_m += kDegPerRad * r;
            ++s.segments;
        }
        if (s.segments == 0) continue;
        t_sum += s.translation_pct;
        r_sum += s.rotation_deg_per_m;
        count += s.segments;
        s.translation_pct /= static_cast<double>(s.segments);
        s.rotation_deg_per_m /= static_cast<double>(s.segments);
        out.lengths.push_back(s);
    }
    if (count > 0) {
        out.translation_pct = t_sum / static_cast<double>(count);
        out.rotation_deg_per_m = r_sum / static_cast<double>(count);
    }
    // End points, each in its own world (the first frame's camera for both).
    const odometry::Pose est_end = estimate.front().inverse() * estimate.back();
    const odometry::Pose true_end = truth.front().inverse() * truth.back();
    out.end_point_m = (est_end.topRightCorner<3, 1>() - true_end.topRightCorner<3, 1>()).norm();
    out.end_point_pct = out.path_m > 0.0 ? 100.0 * out.end_point_m / out.path_m : 0.0;
    return out;
}

nlohmann::json OdometryErrors::to_json() const {
    nlohmann::json per_length = nlohmann::json::array();
    for (const auto& s : lengths) {
        per_length.push_back({{"length_m", s.length_m},
                              {"segments", s.segments},
                              {"translation_pct", s.translation_pct},
                              {"rotation_deg_per_m", s.rotation_deg_per_m}});
    }
    return {{"frames", frames},
            {"path_m", path_m},
            {"lengths", per_length},
            {"translation_pct", translation_pct},
            {"rotation_deg_per_m", rotation_deg_per_m},
            {"end_point_m", end_point_m},
            {"end_point_pct", end_point_pct}};
}

}  // namespace cloud_analysis
