#include <cmath>

#include <catch2/catch.hpp>
#include <glm/glm.hpp>

#include "scene_viewer/ecs/coordinates.hpp"
#include "scene_viewer/views/views.hpp"
#include "stereoscene/support/angles.hpp"

using stereoscene::support::kPi;

using namespace scene_viewer;

namespace {
bool near(const glm::vec3& a, const glm::vec3& b, float tol = 1e-5f) {
    return glm::length(a - b) < tol;
}
}  // namespace

TEST_CASE(
    "KITTI camera axes become OpenGL axes: right stays right, down becomes -up, forward "
    "becomes -z",
    "[coordinates]") {
    CHECK(near(kitti_to_gl({1, 0, 0}), {1, 0, 0}));
    CHECK(near(kitti_to_gl({0, 1, 0}), {0, -1, 0}));
    CHECK(near(kitti_to_gl({0, 0, 1}), {0, 0, -1}));
    CHECK(near(kitti_to_gl({2, 3, 4}), {2, -3, -4}));
}

TEST_CASE("The heading of theta = -pi/2 points forward (+z) and theta = 0 points right (+x)",
          "[coordinates]") {
    CHECK(near(heading_kitti(-kPi / 2), {0, 0, 1}));
    CHECK(near(heading_kitti(0.0), {1, 0, 0}));
    CHECK(near(heading_kitti(kPi / 2), {0, 0, -1}));
}

TEST_CASE("The box world matrix turns the model front (+Z) onto the entity heading for any theta",
          "[coordinates]") {
    for (double theta : {-kPi / 2, 0.0, 0.3, 1.2, kPi / 2, 2.5, -2.9}) {
        const glm::mat4 m = box_world_matrix({0, 0, 0}, theta, {1, 1, 1});
        const glm::vec3 front_gl = glm::vec3(m * glm::vec4(0, 0, 1, 0));
        CHECK(near(front_gl, kitti_to_gl(heading_kitti(theta))));
        const glm::vec3 up_gl = glm::vec3(m * glm::vec4(0, 1, 0, 0));
        CHECK(near(up_gl, {0, 1, 0}));
    }
}

TEST_CASE("The box world matrix scales the unit cube to W, H, L and places it at the centre",
          "[coordinates]") {
    // A car heading forward (theta = -pi/2) at x=5, y=1, z=20 of 1.8 x 1.5 x 4.2 m.
    const glm::mat4 m = box_world_matrix({5, 1, 20}, -kPi / 2, {1.8f, 1.5f, 4.2f});
    CHECK(near(glm::vec3(m * glm::vec4(0, 0, 0, 1)), kitti_to_gl({5, 1, 20})));
    // The model's front face centre lies L/2 further forward in KITTI z.
    CHECK(near(glm::vec3(m * glm::vec4(0, 0, 0.5f, 1)), kitti_to_gl({5, 1, 22.1f}), 1e-4f));
    // The model's right side (+X, seen from behind, model facing +Z) is W/2 to one side.
    const glm::vec3 side = glm::vec3(m * glm::vec4(0.5f, 0, 0, 1)) - kitti_to_gl({5, 1, 20});
    CHECK(std::abs(glm::length(side) - 0.9f) < 1e-4f);
    // The top of the model (+Y) is H/2 above, i.e. smaller KITTI y.
    CHECK(near(glm::vec3(m * glm::vec4(0, 0.5f, 0, 1)), kitti_to_gl({5, 0.25f, 20}), 1e-4f));
}

TEST_CASE("Model bounds are fitted onto the unit cube centred at the origin", "[coordinates]") {
    const glm::mat4 fit = fit_bounds_to_unit_cube({-1, 0, -2}, {3, 2, 6});
    CHECK(near(glm::vec3(fit * glm::vec4(-1, 0, -2, 1)), {-0.5f, -0.5f, -0.5f}));
    CHECK(near(glm::vec3(fit * glm::vec4(3, 2, 6, 1)), {0.5f, 0.5f, 0.5f}));
}

TEST_CASE("The camera view projects a KITTI point onto the pixel the pinhole model gives",
          "[coordinates][views]") {
    const scene_schema::CameraIntrinsics k{1242, 375, 721.5377, 721.5377, 609.5593, 172.854, 0.54};
    for (const glm::vec3 p : {glm::vec3(0, 0, 10), glm::vec3(2, 1, 15), glm::vec3(-5, -2, 30)}) {
        for (const auto& [w, h] : {std::pair{1242, 375}, std::pair{621, 188}}) {
            const glm::mat4 proj = projection_from_intrinsics(k, w, h, 0.1f, 500.0f);
            const glm::vec4 clip = proj * glm::vec4(kitti_to_gl(p), 1.0f);
            const glm::vec3 ndc = glm::vec3(clip) / clip.w;
            const double nx = ndc.x, ny = ndc.y;
            const double px = p.x, py = p.y, pz = p.z;
            const double u = (nx + 1.0) * 0.5 * w;  // pixels from the left
            const double v = (1.0 - ny) * 0.5 * h;  // pixels from the top
            const double sx = static_cast<double>(w) / k.width_px;
            const double sy = static_cast<double>(h) / k.height_px;
            CHECK(u == Approx((k.fx_px * px / pz + k.cx_px) * sx).margin(1e-3));
            CHECK(v == Approx((k.fy_px * py / pz + k.cy_px) * sy).margin(1e-3));
            CHECK(ndc.z > -1.0f);
            CHECK(ndc.z < 1.0f);
        }
    }
}

TEST_CASE("View names parse and unknown ones are refused", "[views]") {
    CHECK(parse_view_kind("bev") == ViewKind::bev);
    CHECK(parse_view_kind("free") == ViewKind::free);
    CHECK_THROWS_AS(parse_view_kind("top"), std::invalid_argument);
}
