#pragma once

/// Angles: the one definition of pi both tools use, degree conversion and wrapping.

#include <cmath>

namespace stereoscene::support {

inline constexpr double kPi = 3.14159265358979323846;
inline constexpr double kHalfPi = kPi / 2.0;
inline constexpr double kTwoPi = 2.0 * kPi;
inline constexpr double kDegPerRad = 180.0 / kPi;

/// Degrees of `radians`.
inline constexpr double degrees(double radians) { return radians * kDegPerRad; }

/// Radians of `deg`.
inline constexpr double radians(double deg) { return deg / kDegPerRad; }

/// `radians` wrapped to one turn around 0, [-pi, pi).
inline double wrap_angle(double radians) {
    double a = std::fmod(radians + kPi, kTwoPi);
    if (a < 0.0) a += kTwoPi;
    return a - kPi;
}

}  // namespace stereoscene::support
