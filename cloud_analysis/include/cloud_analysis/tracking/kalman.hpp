#pragma once

/// A constant-velocity Kalman filter in the ground plane (x right, z forward; metres and
/// m/s): state (x, z, vx, vz), measurement (x, z). Process noise is white acceleration
/// (Bar-Shalom, Li & Kirubarajan 2001, "discrete white noise acceleration" model), as in
/// AB3DMOT (Weng et al. 2020) restricted to the ground plane.

#include <algorithm>
#include <cmath>
#include <deque>
#include <vector>

#include <Eigen/Core>

namespace cloud_analysis::tracking {

/// Noise of the filter.
struct KalmanOptions {
    double acceleration_sigma_mps2 = 1.5;  ///< process noise: std of the acceleration, m/s^2
    /// Measurement noise along the viewing ray near the camera (std), metres.
    double position_sigma_m = 0.25;
    /// Stereo depth error grows with the square of the range (z^2 sigma_d / (f B)): along
    /// the viewing ray the measurement's std is max(position_sigma_m, this * range^2),
    /// metres per square metre.
    double range_sigma_per_m2 = 0.0011;
    /// Across the viewing ray a box centre holds to the box fit's error, not the depth's:
    /// this std whatever the range, metres.
    double across_sigma_m = 0.35;
    double initial_speed_sigma_mps = 10.0;  ///< std of the unknown velocity at birth, m/s
    /// Throws std::invalid_argument naming the bad field.
    void validate() const;
};

/// One frame of a filter, as a smoother needs it: the prediction into this frame from the
/// step before and the state after this frame's measurement (the prediction when it had none).
struct KalmanStep {
    /// The linear part of the map from the step before's state (in its frame) to this
    /// prediction (in this frame): the camera's motion, then the motion model.
    Eigen::Matrix4d transition = Eigen::Matrix4d::Identity();
    Eigen::Vector4d predicted = Eigen::Vector4d::Zero();
    Eigen::Matrix4d predicted_covariance = Eigen::Matrix4d::Identity();
    Eigen::Vector4d filtered = Eigen::Vector4d::Zero();
    Eigen::Matrix4d filtered_covariance = Eigen::Matrix4d::Identity();
    bool first = false;  ///< the filter was born in this frame: no step before it
};

/// Rauch-Tung-Striebel smoothing (Rauch, Tung & Striebel 1965; Bar-Shalom et al. 2001, 8.6):
/// each step's state given every measurement up to the last step, oldest first. A step marked
/// `first` starts the chain; the steps before it are returned as filtered.
std::vector<Eigen::Vector4d> smooth_states(const std::deque<KalmanStep>& steps);

/// One object's state and covariance.
class GroundKalman {
  public:
    /// A track born at (x, z) with unknown velocity.
    GroundKalman(double x_m, double z_m, const KalmanOptions& options);
    /// Moves the state dt seconds ahead (dt >= 0).
    void predict(double dt_s);
    /// Corrects with a measured position (its noise from its range).
    void update(double x_m, double z_m);
    /// Moves the state into another ground frame: position p -> R p + t, velocity v -> R v,
    /// covariance rotated alike (the camera moved; R is a rotation of the ground plane).
    void change_frame(const Eigen::Matrix2d& R, const Eigen::Vector2d& t);
    /// Squared Mahalanobis distance of a measurement from the predicted one.
    double mahalanobis2(double x_m, double z_m) const;
    /// Measurement noise (std, metres) along the viewing ray of a position at this
    /// bird's-eye range.
    double measurement_sigma_m(double range_m) const;
    /// Measurement covariance of a position measured at (x, z): measurement_sigma_m along
    /// the viewing ray, across_sigma_m across it.
    Eigen::Matrix2d measurement_covariance(double x_m, double z_m) const;

    /// This frame's step (what predict, change_frame and update did since the last call),
    /// and starts the next one.
    KalmanStep close_step();

    double x_m() const { return state_(0); }
    double z_m() const { return state_(1); }
    double vx_mps() const { return state_(2); }
    double vz_mps() const { return state_(3); }
    const Eigen::Matrix4d& covariance() const { return covariance_; }

  private:
    Eigen::Vector4d state_;
    Eigen::Matrix4d covariance_;
    KalmanOptions options_;
    KalmanStep step_;  ///< the step being built: its transition and prediction so far
};

/// The hypothesis that an object stands still, tested on a straight-line fit of all its
/// measured positions: the filter above without acceleration (a constant velocity over the
/// whole track, least squares under a weak prior), whose velocity is zero within its own
/// uncertainty at 99 % (chi-square with 2 degrees of freedom). A parked car seen far away is
/// still though its velocity is known only to a few m/s; a car driving slowly for a second
/// near by is not, though the tracker's own filter (which lets it accelerate) cannot yet tell.
class StillHypothesis {
  public:
    /// Starts from a first measured position.
    StillHypothesis(double x_m, double z_m, const KalmanOptions& options);
    void predict(double dt_s) { fit_.predict(dt_s); }
    void update(double x_m, double z_m) { fit_.update(x_m, z_m); }
    void change_frame(const Eigen::Matrix2d& R, const Eigen::Vector2d& t) {
        fit_.change_frame(R, t);
    }
    /// Whether the fitted velocity is zero within its 99 % ellipse.
    bool consistent() const;
    /// The larger std of the fitted velocity's components, m/s.
    double velocity_sigma_mps() const {
        return std::sqrt(std::max(fit_.covariance()(2, 2), fit_.covariance()(3, 3)));
    }
    /// The fitted position now, metres.
    Eigen::Vector2d position_m() const { return {fit_.x_m(), fit_.z_m()}; }

  private:
    GroundKalman fit_;
};

}  // namespace cloud_analysis::tracking
