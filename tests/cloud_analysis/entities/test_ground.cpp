#include <cmath>
#include <random>

#include <catch2/catch.hpp>

#include "cloud_analysis/entities/ground.hpp"

using cloud_analysis::fit_ground_plane;
using cloud_analysis::GroundOptions;

namespace {

/// Points of the plane y = h + slope * z over a 10 m x 30 m patch, plus clutter above it.
std::vector<Eigen::Vector3f> plane_with_clutter(double h, double slope, int clutter) {
    std::vector<Eigen::Vector3f> pts;
    std::mt19937 rng(7);
    std::uniform_real_distribution<double> noise(-0.02, 0.02);
    for (double x = -5.0; x <= 5.0; x += 0.2) {
        for (double z = 3.0; z <= 33.0; z += 0.3) {
            pts.emplace_back(x, h + slope * z + noise(rng), z);
        }
    }
    std::uniform_real_distribution<double> ux(-5.0, 5.0), uy(-3.0, 1.0), uz(3.0, 33.0);
    for (int i = 0; i < clutter; ++i) pts.emplace_back(ux(rng), uy(rng), uz(rng));
    return pts;
}

}  // namespace

TEST_CASE("a flat road 1.65 m below the camera gives height 1.65 and normal -y", "[ground]") {
    const auto plane = fit_ground_plane(plane_with_clutter(1.65, 0.0, 2000), GroundOptions{});
    REQUIRE(plane.has_value());
    CHECK(plane->camera_height_m() == Approx(1.65).margin(0.01));
    CHECK(plane->normal.y() == Approx(-1.0).margin(1e-3));
    CHECK(plane->height(Eigen::Vector3d(0.0, 1.65, 10.0)) == Approx(0.0).margin(0.01));
    CHECK(plane->height(Eigen::Vector3d(0.0, 0.65, 10.0)) == Approx(1.0).margin(0.01));
}

TEST_CASE("a road rising ahead gives the tilted normal", "[ground]") {
    // y = 1.6 - 0.05 z: the road rises 5 cm per metre; normal ~ (0, -1, -0.05) normalised.
    const auto plane = fit_ground_plane(plane_with_clutter(1.6, -0.05, 500), GroundOptions{});
    REQUIRE(plane.has_value());
    const Eigen::Vector3d expected = Eigen::Vector3d(0.0, -1.0, -0.05).normalized();
    CHECK(plane->normal.dot(expected) == Approx(1.0).margin(1e-4));
    CHECK(plane->camera_height_m() == Approx(1.6 / std::sqrt(1.0 + 0.05 * 0.05)).margin(0.01));
}

TEST_CASE("a wall or too few points give no ground plane", "[ground]") {
    std::vector<Eigen::Vector3f> wall;
    for (double y = -2.0; y <= 1.5; y += 0.05) {
        for (double z = 5.0; z <= 20.0; z += 0.1) wall.emplace_back(3.0f, y, z);
    }
    CHECK_FALSE(fit_ground_plane(wall, GroundOptions{}).has_value());
    CHECK_FALSE(fit_ground_plane({}, GroundOptions{}).has_value());
}

TEST_CASE("ground options name the bad field", "[ground]") {
    GroundOptions o;
    o.inlier_distance_m = 0.0;
    CHECK_THROWS_WITH(o.validate(), Catch::Contains("inlier_distance_m"));
}
