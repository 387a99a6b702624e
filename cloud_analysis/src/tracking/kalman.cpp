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
    positive(initial_speed_sigma_mps, "initial_speed_sigma_mps");
    if (!(range_sigma_per_m2 >= 0.0 && std::isfinite(range_sigma_per_m2))) {
        throw std::invalid_argument("range_sigma_per_m2 must be >= 0");
    }
}

GroundKalman::GroundKalman(double x_m, double z_m, const KalmanOptions& options)
    : options_(options) {
    state_ << x_m, z_m, 0.0, 0.0;
    const double sigma = measurement_sigma_m(std::hypot(x_m, z_m));
    const double p2 = sigma * sigma;
    const double v2 = options.initial_speed_sigma_mps * options.initial_speed_sigma_mps;
    covariance_ = Eigen::Vector4d(p2, p2, v2, v2).asDiagonal();
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
}

namespace {

Eigen::Matrix2d innovation_covariance(const Eigen::Matrix4d& P, double r2) {
    return P.topLeftCorner<2, 2>() + Eigen::Matrix2d::Identity() * r2;
}

}  // namespace

double GroundKalman::measurement_sigma_m(double range_m) const {
    return std::max(options_.position_sigma_m, options_.range_sigma_per_m2 * range_m * range_m);
}

void GroundKalman::update(double x_m, double z_m) {
    const double sigma = measurement_sigma_m(std::hypot(x_m, z_m));
    const double r2 = sigma * sigma;
    const Eigen::Matrix2d S = innovation_covariance(covariance_, r2);
    const Eigen::Matrix<double, 4, 2> K = covariance_.leftCols<2>() * S.inverse();
    const Eigen::Vector2d innovation(x_m - state_(0), z_m - state_(1));
    state_ += K * innovation;
    Eigen::Matrix<double, 2, 4> H = Eigen::Matrix<double, 2, 4>::Zero();
    H(0, 0) = H(1, 1) = 1.0;
    // Joseph form keeps the covariance symmetric and positive definite.
    const Eigen::Matrix4d I_KH = Eigen::Matrix4d::Identity() - K * H;
    covariance_ = I_KH * covariance_ * I_KH.transpose() + K * (r2 * K.transpose());
}

double GroundKalman::mahalanobis2(double x_m, double z_m) const {
    const double sigma = measurement_sigma_m(std::hypot(x_m, z_m));
    const double r2 = sigma * sigma;
    const Eigen::Vector2d innovation(x_m - state_(0), z_m - state_(1));
    return innovation.dot(innovation_covariance(covariance_, r2).inverse() * innovation);
}

}  // namespace cloud_analysis::tracking
