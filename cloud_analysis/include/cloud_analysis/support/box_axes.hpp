#pragma once

/// The ground-plane axes of an upright box (docs/format.md): offsets from its centre along its
/// heading (cos t, 0, -sin t) and across it (sin t, 0, cos t), the projection every footprint
/// test uses.

#include <array>
#include <cmath>

#include <Eigen/Core>

namespace cloud_analysis {

struct BoxAxes {
    double c = 1.0;  ///< cos theta
    double s = 0.0;  ///< sin theta
    explicit BoxAxes(double theta_rad) : c(std::cos(theta_rad)), s(std::sin(theta_rad)) {}
    /// The offset (dx, dz) from the box centre along the heading, metres.
    double along(double dx, double dz) const { return dx * c - dz * s; }
    /// The offset (dx, dz) from the box centre across the heading, metres.
    double across(double dx, double dz) const { return dx * s + dz * c; }
    /// The corners of a footprint centred at (x, z), L long along the heading and W wide
    /// across it, counter-clockwise in (x, z).
    std::array<Eigen::Vector2d, 4> corners(double x, double z, double L, double W) const {
        const Eigen::Vector2d centre(x, z);
        const Eigen::Vector2d hl = 0.5 * L * Eigen::Vector2d(c, -s);  // along the heading
        const Eigen::Vector2d aw = 0.5 * W * Eigen::Vector2d(s, c);   // across it
        return {centre - hl - aw, centre + hl - aw, centre + hl + aw, centre - hl + aw};
    }
};

}  // namespace cloud_analysis
