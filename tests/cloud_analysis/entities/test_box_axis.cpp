#include <cmath>
#include <random>
#include <vector>

#include <catch2/catch.hpp>

#include "cloud_analysis/entities/boxes.hpp"

using namespace cloud_analysis;

namespace {

/// Points 5 cm apart on the long side and the end facing the camera of a car centred at (x0, z0)
/// heading +z turned by `turn_rad` towards +x, each pushed along the viewing ray by stereo-like
/// noise (std 0.02 m per metre of range); only the side when `side_only`.
std::vector<Eigen::Vector3f> car_faces(double x0, double z0, double turn_rad, bool side_only) {
    std::mt19937 rng(11);
    std::normal_distribution<double> unit(0.0, 1.0);
    const double L = 4.4, W = 1.8, H = 1.45, ground_y = 1.65;
    const Eigen::Vector2d along(std::sin(turn_rad), std::cos(turn_rad));  // (x, z)
    const Eigen::Vector2d across(along.y(), -along.x());
    std::vector<Eigen::Vector3f> pts;
    const auto add = [&](const Eigen::Vector2d& xz) {
        for (double y = ground_y - 0.3; y >= ground_y - H; y -= 0.05) {
            const double r = xz.norm();
            const Eigen::Vector2d p = xz + (0.02 * r * unit(rng)) * xz / r;
            pts.emplace_back(static_cast<float>(p.x()), static_cast<float>(y),
                             static_cast<float>(p.y()));
        }
    };
    const Eigen::Vector2d c(x0, z0);
    // The side and the end nearer the camera.
    const Eigen::Vector2d side = (c - across).norm() < (c + across).norm() ? -across : across;
    const Eigen::Vector2d end = (c - along).norm() < (c + along).norm() ? -along : along;
    for (double a = -L / 2.0; a <= L / 2.0; a += 0.05) add(c + 0.5 * W * side + a * along);
    if (!side_only) {
        for (double b = -W / 2.0; b <= W / 2.0; b += 0.05) add(c + 0.5 * L * end + b * across);
    }
    return pts;
}

void check_same(const OrientedBox& a, const OrientedBox& b) {
    CHECK(a.theta == b.theta);
    CHECK(a.centre_m == b.centre_m);
    CHECK(a.L_m == b.L_m);
    CHECK(a.W_m == b.W_m);
    CHECK(a.H_m == b.H_m);
}

}  // namespace

TEST_CASE("a refit on the axis an earlier fit chose is the full fit with the new trimming",
          "[boxes]") {
    GroundPlane ground;
    ground.normal = Eigen::Vector3d(0.0, -1.0, 0.0);
    ground.d = 1.65;
    for (const bool side_only : {false, true}) {
        // Parked ahead-right along the road, seen on its side and rear; or crossing ahead,
        // broadside, its long side alone in view.
        const auto pts =
            side_only ? car_faces(0.5, 12.0, 1.62, true) : car_faces(3.5, 16.0, 0.08, false);
        BoxFitOptions o;
        o.prior_L_m = 4.2;
        o.prior_W_m = 1.8;
        o.prior_H_m = 1.5;
        o.disparity_fb_px_m = 389.0;
        FootprintAxis axis;
        const OrientedBox first = fit_upright_box(pts, ground, o, axis);
        CAPTURE(side_only, axis.angle_rad, axis.face_is_length);
        // Broadside, the long straight face sets the axis; seen on two sides, the L-shape.
        CHECK(axis.face_is_length == side_only);
        check_same(fit_upright_box_on_axis(pts, ground, o, axis), first);
        BoxFitOptions trimmed = o;
        trimmed.near_trim_fraction = 0.1;
        trimmed.area_weighted_extents = true;
        FootprintAxis again;
        const OrientedBox full = fit_upright_box(pts, ground, trimmed, again);
        CHECK(again.angle_rad == axis.angle_rad);
        CHECK(again.face_is_length == axis.face_is_length);
        check_same(fit_upright_box_on_axis(pts, ground, trimmed, axis), full);
    }
    CHECK_THROWS_AS(fit_upright_box_on_axis({}, ground, BoxFitOptions{}, FootprintAxis{}),
                    std::invalid_argument);
}
