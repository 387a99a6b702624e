#pragma once

/// Angles in radians.

#include <cmath>

namespace cloud_analysis {

/// `radians` wrapped to one turn around 0, [-pi, pi).
inline double wrap_angle(double radians) {
    constexpr double kTurn = 6.28318530717958647692;
    double a = std::fmod(radians + kTurn / 2.0, kTurn);
    if (a < 0.0) a += kTurn;
    return a - kTurn / 2.0;
}

}  // namespace cloud_analysis
