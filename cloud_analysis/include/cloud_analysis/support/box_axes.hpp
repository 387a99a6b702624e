#pragma once

/// The ground-plane axes of an upright box (docs/format.md): offsets from its centre along its
/// heading (cos t, 0, -sin t) and across it (sin t, 0, cos t), the projection every footprint
/// test uses.

#include <cmath>

namespace cloud_analysis {

struct BoxAxes {
    double c = 1.0;  ///< cos theta
    double s = 0.0;  ///< sin theta
    explicit BoxAxes(double theta_rad) : c(std::cos(theta_rad)), s(std::sin(theta_rad)) {}
    /// The offset (dx, dz) from the box centre along the heading, metres.
    double along(double dx, double dz) const { return dx * c - dz * s; }
    /// The offset (dx, dz) from the box centre across the heading, metres.
    double across(double dx, double dz) const { return dx * s + dz * c; }
};

}  // namespace cloud_analysis
