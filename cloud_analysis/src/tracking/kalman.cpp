#include "cloud_analysis/tracking/kalman.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

#include <Eigen/Dense>

namespace cloud_analysis::tracking {

void KalmanOptions::validate() const {
    auto positive = [](double v, const char* name) {
        if (!(v > 0.0 && std::isfinite(v))) {
            throw std::invalid_argument(std::string(name) + " must be > 0");
        }
    };
    positive(acceleration_sigma_mps2, "acceleration_sigma_mps2");
    positive(position_sigma_m, "position_sigma_m");
    positive(across_sigma_m, "across_sigma_m");
    positive(initial_speed_sigma_mps, "initial_speed_sigma_mps");
    if (!(range_sigma_per_m2 >= 0.0 && std::isfinite(range_sigma_per_m2))) {
        throw std::invalid_argument("range_sigma_per_m2 must be >= 0");
    }
}

GroundKalman::GroundKalman(double x_m, double z_m, const KalmanOptions& options)
    : options_(options) {
    state_ << x_m, z_m, 0.0, 0.0;
    const double v2 = options.initial_speed_sigma_mps * options.initial_speed_sigma_mps;
    covariance_ = Eigen::Vector4d(0.0, 0.0, v2, v2).asDiagonal();
    covariance_.topLeftCorner<2, 2>() = measurement_covariance(x_m, z_m);
    step_.first = true;
    step_.predicted = state_;
    step_.predicted_covariance = covariance_;
}

void GroundKalman::predict(double dt_s) {
    if (!(dt_s >= 0.0)) throw std::invalid_argument("predict: dt must be >= 0");
    Eigen::Matrix4d F = Eigen::Matrix4d::Identity();
    F(0, 2) = dt_s;
    F(1, 3) = dt_s;
    // Discrete white noise acceleration: G = (dt^2/2, dt) per axis, Q = G G^T sigma_a^2.
    const double q = options_.acceleration_sigma_mps2 * options_.acceleration_sigma_mps2;
    const double dt2 = dt_s * dt_s, dt3 = dt2 * dt_s, dt4 = dt3 * dt_s;
    Eigen::Matrix4d Q = Eigen::Matrix4d::Zero();
    for (int axis = 0; axis < 2; ++axis) {
        Q(axis, axis) = dt4 / 4.0 * q;
        Q(axis, axis + 2) = Q(axis + 2, axis) = dt3 / 2.0 * q;
        Q(axis + 2, axis + 2) = dt2 * q;
    }
    state_ = F * state_;
    covariance_ = F * covariance_ * F.transpose() + Q;
    step_.transition = F * step_.transition;
    step_.predicted = state_;
    step_.predicted_covariance = covariance_;
}

namespace {

Eigen::Matrix2d innovation_covariance(const Eigen::Matrix4d& P, const Eigen::Matrix2d& R) {
    return P.topLeftCorner<2, 2>() + R;
}

}  // namespace

double GroundKalman::measurement_sigma_m(double range_m) const {
    return std::max(options_.position_sigma_m, options_.range_sigma_per_m2 * range_m * range_m);
}

Eigen::Matrix2d GroundKalman::measurement_covariance(double x_m, double z_m) const {
    const double range = std::hypot(x_m, z_m);
    const double along = measurement_sigma_m(range);
    const double across = options_.across_sigma_m;
    if (!(range > 0.0)) {
        const double sigma = std::max(along, across);
        return Eigen::Matrix2d::Identity() * (sigma * sigma);
    }
    const Eigen::Vector2d ray(x_m / range, z_m / range);
    const Eigen::Vector2d side(ray.y(), -ray.x());
    return along * along * ray * ray.transpose() + across * across * side * side.transpose();
}

void GroundKalman::change_frame(const Eigen::Matrix2d& R, const Eigen::Vector2d& t) {
    Eigen::Matrix4d M = Eigen::Matrix4d::Zero();
    M.topLeftCorner<2, 2>() = R;
    M.bottomRightCorner<2, 2>() = R;
    state_ = M * state_;
    state_.head<2>() += t;
    covariance_ = M * covariance_ * M.transpose();
    step_.transition = M * step_.transition;
    step_.predicted = state_;
    step_.predicted_covariance = covariance_;
}

KalmanStep GroundKalman::close_step() {
    KalmanStep done = step_;
    done.filtered = state_;
    done.filtered_covariance = covariance_;
    step_ = KalmanStep{};
    step_.predicted = state_;
    step_.predicted_covariance = covariance_;
    return done;
}

std::vector<Eigen::Vector4d> smooth_states(const std::deque<KalmanStep>& steps) {
    std::vector<Eigen::Vector4d> out(steps.size());
    if (steps.empty()) return out;
    out.back() = steps.back().filtered;
    for (std::size_t k = steps.size() - 1; k-- > 0;) {
        const KalmanStep& now = steps[k];
        const KalmanStep& next = steps[k + 1];
        if (next.first) {
            // A chain starts after this step: nothing later speaks for it.
            out[k] = now.filtered;
            continue;
        }
        // Gain G = P_k|k A^T P_k+1|k^-1; the camera's translation cancels in the difference.
        const Eigen::Matrix4d G = now.filtered_covariance * next.transition.transpose() *
                                  next.predicted_covariance.inverse();
        out[k] = now.filtered + G * (out[k + 1] - next.predicted);
    }
    return out;
}

void GroundKalman::update(double x_m, double z_m) {
    const Eigen::Matrix2d R = measurement_covariance(x_m, z_m);
    const Eigen::Matrix2d S = innovation_covariance(covariance_, R);
    const Eigen::Matrix<double, 4, 2> K = covariance_.leftCols<2>() * S.inverse();
    const Eigen::Vector2d innovation(x_m - state_(0), z_m - state_(1));
    state_ += K * innovation;
    Eigen::Matrix<double, 2, 4> H = Eigen::Matrix<double, 2, 4>::Zero();
    H(0, 0) = H(1, 1) = 1.0;
    // Joseph form keeps the covariance symmetric and positive definite.
    const Eigen::Matrix4d I_KH = Eigen::Matrix4d::Identity() - K * H;
    covariance_ = I_KH * covariance_ * I_KH.transpose() + K * R * K.transpose();
}

double GroundKalman::mahalanobis2(double x_m, double z_m) const {
    const Eigen::Vector2d innovation(x_m - state_(0), z_m - state_(1));
    return innovation.dot(
        innovation_covariance(covariance_, measurement_covariance(x_m, z_m)).inverse() *
        innovation);
}

namespace {

/// The filter's settings without acceleration (validate needs some: a millionth of a g).
KalmanOptions without_acceleration(KalmanOptions o) {
    o.acceleration_sigma_mps2 = 1e-5;
    return o;
}

}  // namespace

StillHypothesis::StillHypothesis(double x_m, double z_m, const KalmanOptions& options)
    : fit_(x_m, z_m, without_acceleration(options)) {}

bool StillHypothesis::consistent() const {
    constexpr double kChiSquare2Dof99 = 9.2103;  // -2 ln 0.01
    const Eigen::Matrix2d P = fit_.covariance().bottomRightCorner<2, 2>();
    const Eigen::Vector2d v(fit_.vx_mps(), fit_.vz_mps());
    return v.dot(P.inverse() * v) <= kChiSquare2Dof99;
}

}  // namespace cloud_analysis::tracking
