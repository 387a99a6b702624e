#include <algorithm>
#include <cmath>
#include <fstream>
#include <random>
#include <sstream>
#include <string>

#include <catch2/catch.hpp>

#include "cloud_analysis/entities/boxes.hpp"
#include "cloud_analysis/entities/cluster.hpp"
#include "stereoscene/support/angles.hpp"

using stereoscene::support::wrap_angle;

using namespace cloud_analysis;

namespace {

using stereoscene::support::kPi;
/// tan of the angle between the optical axis and the image's right edge in the edge tests.
const double kRightEdge = std::tan(40.0 * kPi / 180.0);

/// Points on the vertical faces of an upright box standing on y = ground_y, centre (x, z),
/// yaw t (heading (cos t, 0, -sin t)); only faces turned to the camera when visible_only.
std::vector<Eigen::Vector3f> box_faces(double x, double z, double t, double L, double W, double H,
                                       double ground_y, bool visible_only) {
    const Eigen::Vector3d c(x, ground_y - H / 2.0, z);
    const Eigen::Vector3d h(std::cos(t), 0.0, -std::sin(t));
    const Eigen::Vector3d s(std::sin(t), 0.0, std::cos(t));
    std::vector<Eigen::Vector3f> pts;
    struct Face {
        Eigen::Vector3d normal, along;
        double offset, half;
    };
    const Face faces[] = {{h, s, L / 2.0, W / 2.0},
                          {-h, s, L / 2.0, W / 2.0},
                          {s, h, W / 2.0, L / 2.0},
                          {-s, h, W / 2.0, L / 2.0}};
    for (const Face& f : faces) {
        const Eigen::Vector3d centre = c + f.offset * f.normal;
        if (visible_only && f.normal.dot(-centre) <= 0.0) continue;
        for (double a = -f.half; a <= f.half + 1e-9; a += 0.05) {
            for (double y = -H / 2.0; y <= H / 2.0 + 1e-9; y += 0.05) {
                pts.push_back((centre + a * f.along + Eigen::Vector3d(0.0, y, 0.0)).cast<float>());
            }
        }
    }
    return pts;
}

/// A camera's pixel column on a surface at (x, z): points every 5 cm of height from 0.3 m to
/// 1.4 m above a road at y = 1.65.
void add_column(std::vector<Eigen::Vector3f>& pts, double x, double z) {
    for (double y = 1.65 - 0.3; y >= 1.65 - 1.4; y -= 0.05) {
        pts.emplace_back(static_cast<float>(x), static_cast<float>(y), static_cast<float>(z));
    }
}

/// Difference of two yaws modulo pi (front and back of a box look alike).
double yaw_error_mod_pi(double a, double b) {
    double d = std::fmod(std::abs(a - b), kPi);
    return std::min(d, kPi - d);
}

GroundPlane flat_ground(double camera_height_m) {
    GroundPlane g;
    g.normal = Eigen::Vector3d(0.0, -1.0, 0.0);
    g.d = camera_height_m;
    return g;
}

}  // namespace

TEST_CASE("a box of points at a known yaw gives that yaw (mod pi) and its size", "[boxes]") {
    for (double t : {0.0, -0.3, -1.2, -kPi / 2.0, -2.5, 0.7, 2.0}) {
        const auto pts = box_faces(-3.0, 15.0, t, 4.0, 1.8, 1.5, 1.65, false);
        const OrientedBox box = fit_upright_box(pts, flat_ground(1.65), BoxFitOptions{});
        INFO("true yaw " << t << ", fitted " << box.theta);
        CHECK(yaw_error_mod_pi(box.theta, t) < 0.03);
        // The documented convention: the heading points away from the camera, theta in [-pi, 0].
        CHECK(box.theta <= 1e-9);
        CHECK(box.theta >= -kPi - 1e-9);
        CHECK(box.L_m == Approx(4.0).margin(0.15));
        CHECK(box.W_m == Approx(1.8).margin(0.15));
        CHECK(box.H_m == Approx(1.5).margin(0.1));
        CHECK(box.centre_m.x() == Approx(-3.0).margin(0.1));
        CHECK(box.centre_m.y() == Approx(1.65 - 0.75).margin(0.1));
        CHECK(box.centre_m.z() == Approx(15.0).margin(0.1));
    }
}

TEST_CASE("lshape_yaw finds the long side's heading of a rectangle outline", "[boxes]") {
    std::vector<Eigen::Vector2d> xz;
    const double t = -0.6;
    const Eigen::Vector2d h(std::cos(t), -std::sin(t)), s(std::sin(t), std::cos(t));
    for (double a = -2.0; a <= 2.0; a += 0.05) {
        xz.push_back(Eigen::Vector2d(0.0, 10.0) + a * h - 0.9 * s);
    }
    for (double b = -0.9; b <= 0.9; b += 0.05) {
        xz.push_back(Eigen::Vector2d(0.0, 10.0) - 2.0 * h + b * s);
    }
    CHECK(yaw_error_mod_pi(lshape_yaw(xz, 0.5), t) < 0.02);
}

TEST_CASE("a car seen on two sides is completed with the prior away from the camera", "[boxes]") {
    // Car ahead-left, parked along the road: only its rear and right side are visible.
    const double t = -kPi / 2.0 + 0.1;
    const auto pts = box_faces(-4.0, 14.0, t, 4.2, 1.8, 1.5, 1.65, true);
    BoxFitOptions o;
    o.prior_L_m = 4.2;
    o.prior_W_m = 1.8;
    o.prior_H_m = 1.5;
    const OrientedBox box = fit_upright_box(pts, flat_ground(1.65), o);
    CHECK(yaw_error_mod_pi(box.theta, t) < 0.05);
    CHECK(box.L_m == Approx(4.2).margin(0.15));
    CHECK(box.W_m == Approx(1.8).margin(0.15));
    CHECK(box.centre_m.x() == Approx(-4.0).margin(0.2));
    CHECK(box.centre_m.z() == Approx(14.0).margin(0.2));
}

TEST_CASE("only the rear of a car visible still gives a car-sized box behind it", "[boxes]") {
    // A car straight ahead heading along +z: the camera sees only its rear face.
    const auto all = box_faces(0.0, 12.0, -kPi / 2.0, 4.2, 1.8, 1.5, 1.65, false);
    std::vector<Eigen::Vector3f> rear;
    for (const auto& p : all) {
        if (p.z() < 12.0f - 2.05f) rear.push_back(p);
    }
    REQUIRE(rear.size() > 10);
    BoxFitOptions o;
    o.prior_L_m = 4.2;
    o.prior_W_m = 1.8;
    const OrientedBox box = fit_upright_box(rear, flat_ground(1.65), o);
    CHECK(yaw_error_mod_pi(box.theta, -kPi / 2.0) < 0.05);
    CHECK(box.L_m == Approx(4.2).margin(0.05));
    CHECK(box.centre_m.z() == Approx(12.0).margin(0.15));
}

TEST_CASE("the near end along the ray trims more: the rear's smear in front of it moves no box",
          "[boxes]") {
    // The rear of a car 25 m straight ahead, its points spread along the ray as stereo spreads
    // them (std 0.5 m): the 2 % quantile lies a metre in front of the face, the 4 % one less.
    const auto all = box_faces(0.0, 25.0, -kPi / 2.0, 4.2, 1.8, 1.5, 1.65, false);
    std::mt19937 rng(7);
    std::normal_distribution<float> smear(0.0f, 0.5f);
    std::vector<Eigen::Vector3f> rear;
    for (const auto& p : all) {
        if (p.z() < 25.0f - 2.05f) rear.push_back(p + Eigen::Vector3f(0.0f, 0.0f, smear(rng)));
    }
    BoxFitOptions o;
    o.prior_L_m = 4.2;
    o.prior_W_m = 1.8;
    const OrientedBox plain = fit_upright_box(rear, flat_ground(1.65), o);
    o.near_trim_fraction = 0.1;
    const OrientedBox trimmed = fit_upright_box(rear, flat_ground(1.65), o);
    // Only the near end moved, away from the camera, towards the true centre.
    CHECK(trimmed.centre_m.z() > plain.centre_m.z() + 0.2);
    CHECK(std::abs(trimmed.centre_m.z() - 25.0) < std::abs(plain.centre_m.z() - 25.0));
    CHECK(trimmed.centre_m.x() == Approx(plain.centre_m.x()).margin(1e-9));
    o.near_trim_fraction = 0.01;
    CHECK_THROWS_WITH(o.validate(), Catch::Contains("near_trim_fraction"));
}

TEST_CASE("a side seen along the ray, thinning out with range, keeps its far end over seen surface",
          "[boxes]") {
    // A 4.8 m car parked on the left, 6-10.8 m ahead: its rear and its inner side sampled as a
    // camera's pixels (f 700 px, one point per column and 5 cm of height), so the side's far
    // metre holds a third of the points its near metre holds. Quantiles of points end the side
    // short, and the 4.2 m prior then stands in for the measured length.
    constexpr double f = 700.0, x_side = -3.9, x_kerb = -5.7, z_near = 6.0, z_far = 10.8;
    std::vector<Eigen::Vector3f> pts;
    const auto column = [&](double x, double z) { add_column(pts, x, z); };
    for (double u = f * x_side / z_near; u <= f * x_side / z_far; u += 1.0)
        column(x_side, f * x_side / u);
    for (double u = f * x_kerb / z_near; u < f * x_side / z_near; u += 1.0)
        column(u * z_near / f, z_near);
    BoxFitOptions o;
    o.prior_L_m = 4.2;
    o.prior_W_m = 1.8;
    const auto far_end = [](const OrientedBox& b) { return b.centre_m.z() + b.L_m / 2.0; };
    const OrientedBox points = fit_upright_box(pts, flat_ground(1.65), o);
    o.area_weighted_extents = true;
    const OrientedBox surface = fit_upright_box(pts, flat_ground(1.65), o);
    CHECK(far_end(points) < z_far - 0.3);
    CHECK(far_end(surface) == Approx(z_far).margin(0.2));
    CHECK(surface.L_m == Approx(z_far - z_near).margin(0.25));
    // One column of range smear 25 m away: at its own range it would weigh 5 % of the surface
    // and end the box there; weighed as at one prior length behind the near end, 1 %.
    column(x_side, 25.0);
    const OrientedBox smeared = fit_upright_box(pts, flat_ground(1.65), o);
    CHECK(far_end(smeared) == Approx(far_end(surface)).margin(0.1));
    // A rig on which one pixel of disparity spans a tenth of the prior from 6.5 m on (f·B 100
    // px m): there smear, not pixel spacing, shapes the far end, and the points weigh alike.
    o.disparity_fb_px_m = 100.0;
    const OrientedBox coarse = fit_upright_box(pts, flat_ground(1.65), o);
    o.area_weighted_extents = false;
    CHECK(far_end(coarse) ==
          Approx(far_end(fit_upright_box(pts, flat_ground(1.65), o))).margin(0.1));
}

TEST_CASE("a side seen along the ray ends where its pixel columns end, not where its points thin",
          "[boxes]") {
    // A 4.7 m car parked on the left, 9-13.7 m ahead: its rear and its inner side sampled as a
    // camera's pixels (f 721 px, one point per column and 5 cm of height). Its box ends 0.5 m
    // short of the side's far end, as quantiles of a far end seen sparsely leave it.
    constexpr double f = 721.0, x_side = -3.9, x_kerb = -5.8, z_near = 9.0, z_far = 13.7;
    std::vector<Eigen::Vector3f> pts;
    const auto column = [&](double x, double z) { add_column(pts, x, z); };
    const auto side_to = [&](double z_end) {
        for (double u = f * x_side / z_near; u <= f * x_side / z_end; u += 1.0)
            column(x_side, f * x_side / u);
    };
    for (double u = f * x_kerb / z_near; u < f * x_side / z_near; u += 1.0)
        column(u * z_near / f, z_near);
    side_to(z_far);
    OrientedBox box;
    box.theta = -kPi / 2.0;  // heading +z, away from the camera
    box.L_m = 4.2;
    box.W_m = 1.9;
    box.H_m = 1.4;
    box.centre_m = Eigen::Vector3d(x_side - 0.95, 0.95, z_near + 2.1);
    const auto far_end = [](const OrientedBox& b) { return b.centre_m.z() + b.L_m / 2.0; };
    const auto near_end = [](const OrientedBox& b) { return b.centre_m.z() - b.L_m / 2.0; };
    const OrientedBox out = far_end_to_columns(box, pts, 6.0);
    CHECK(far_end(out) == Approx(z_far).margin(0.1));
    CHECK(near_end(out) == Approx(z_near).margin(1e-9));
    CHECK(out.centre_m.x() == Approx(box.centre_m.x()).margin(1e-9));
    CHECK(out.theta == box.theta);
    // At most max_length_m long.
    CHECK(far_end_to_columns(box, pts, 4.5).L_m == Approx(4.5).margin(1e-9));
    // A few stray points at a farther column (smear, label bleed) do not move it.
    for (int k = 0; k < 5; ++k) {
        pts.emplace_back(static_cast<float>(x_side), 1.0f, static_cast<float>(z_far + 2.0));
    }
    CHECK(far_end(far_end_to_columns(box, pts, 6.0)) == Approx(z_far).margin(0.1));
    // Never beyond the points: a side that ends where the box does leaves it as it is.
    pts.clear();
    side_to(far_end(box));
    const OrientedBox short_side = far_end_to_columns(box, pts, 6.0);
    CHECK(short_side.L_m == Approx(box.L_m).margin(0.05));
    // A length across the viewing ray (a car crossing ahead) is left alone.
    OrientedBox across = box;
    across.theta = 0.0;
    across.centre_m = Eigen::Vector3d(0.0, 0.95, 11.0);
    CHECK(
        far_end_to_columns(across, box_faces(0.0, 11.0, 0.0, 4.7, 1.8, 1.4, 1.65, true), 6.0).L_m ==
        across.L_m);
    // The same car 16 m farther: its side's far end seen at 7.5 degrees from the side, where
    // 5 cm of stereo error across the side moves the end by 0.4 m: left as it is.
    OrientedBox far_box = box;
    far_box.centre_m.z() += 16.0;
    CHECK(far_end_to_columns(
              far_box,
              box_faces(x_side - 0.95, z_near + 16.0 + 2.35, -kPi / 2.0, 4.7, 1.9, 1.4, 1.65, true),
              6.0)
              .L_m == far_box.L_m);
}

TEST_CASE("with its own outline, a side's far end follows the taper and may come nearer",
          "[boxes]") {
    // A 3.6 m car parked on the right, 9-12.6 m ahead, sampled as a camera's pixel columns (f
    // 721 px): its side at x 3.9 m, tapering to 4.0 m over its last 0.4 m. Its box, completed to
    // a 4.2 m prior, reaches 0.6 m past the car.
    constexpr double f = 721.0, z_near = 9.0, z_far = 12.6;
    const auto x_side = [&](double z) {
        return z < z_far - 0.4 ? 3.9 : 3.9 + (z - z_far + 0.4) / 4.0;
    };
    std::vector<Eigen::Vector3f> pts;
    for (double u = f * 5.8 / z_near; u > f * 3.9 / z_near; u -= 1.0) {
        add_column(pts, u * z_near / f, z_near);
    }
    for (double z = z_near; z <= z_far; z += 0.01) add_column(pts, x_side(z), z);
    OrientedBox box;
    box.theta = -kPi / 2.0;  // heading +z, away from the camera
    box.L_m = 4.2;
    box.W_m = 1.9;
    box.H_m = 1.4;
    box.centre_m = Eigen::Vector3d(3.9 + 0.95, 0.95, z_near + 2.1);
    const auto far_end = [](const OrientedBox& b) { return b.centre_m.z() + b.L_m / 2.0; };
    const auto near_end = [](const OrientedBox& b) { return b.centre_m.z() - b.L_m / 2.0; };
    // Without an instance image: never nearer.
    CHECK(far_end_to_columns(box, pts, 6.0).L_m == box.L_m);
    // The outline the car's own on the image's left, where its far end is: the far end where
    // the outermost column meets the tapered side.
    const OrientedBox own = far_end_to_columns(box, pts, 6.0, std::array<bool, 2>{true, false});
    CHECK(far_end(own) == Approx(z_far).margin(0.1));
    CHECK(near_end(own) == Approx(z_near).margin(1e-9));
    // Hidden there (something nearer beside the outline): the prior's length stays.
    CHECK(far_end_to_columns(box, pts, 6.0, std::array<bool, 2>{false, true}).L_m == box.L_m);
    // A longer box of the same car: through the side the box fits (3.9 m), the outermost column
    // meets it 0.3 m short of the car's end; through the outermost points, at its end.
    OrientedBox longer = box;
    longer.L_m = 3.0;
    longer.centre_m.z() = z_near + 1.5;
    CHECK(far_end(far_end_to_columns(longer, pts, 6.0)) < z_far - 0.2);
    CHECK(far_end(far_end_to_columns(longer, pts, 6.0, std::array<bool, 2>{false, false})) ==
          Approx(z_far).margin(0.1));
    // Outermost points moved 15 % farther along their rays (range smear behind its end), 0.6 m
    // inside the side, are no taper: the box's side stands.
    std::vector<Eigen::Vector3f> smeared;
    for (const auto& p : pts)
        smeared.push_back(p.z() > z_far - 0.4 ? Eigen::Vector3f(1.15f * p) : p);
    CHECK(far_end_to_columns(longer, smeared, 6.0, std::array<bool, 2>{false, false}).L_m ==
          Approx(far_end_to_columns(longer, smeared, 6.0).L_m).margin(1e-9));
}

TEST_CASE("the thesis extractors on a uniform box give its centre and size", "[boxes]") {
    std::vector<Eigen::Vector3f> pts;
    // Uniform grid over x in [0, 2], y in [1, 2], z in [1, 5]: centre (1, 1.5, 3), size 2 x 1 x 4.
    for (double x = 0.0; x <= 2.0 + 1e-9; x += 0.05) {
        for (double y = 1.0; y <= 2.0 + 1e-9; y += 0.05) {
            for (double z = 1.0; z <= 5.0 + 1e-9; z += 0.05) pts.emplace_back(x, y, z);
        }
    }
    const Eigen::Vector3d centre(1.0, 1.5, 3.0);
    for (const OrientedBox& box : {average_box(pts), variance_box(pts)}) {
        CHECK((box.centre_m - centre).norm() < 0.05);  // a grid is not quite continuous
        CHECK(box.theta == 0.0);
        CHECK(box.L_m == Approx(2.0).epsilon(0.06));  // along x
        CHECK(box.H_m == Approx(1.0).epsilon(0.06));  // along y
        CHECK(box.W_m == Approx(4.0).epsilon(0.06));  // along z
    }
    const OrientedBox c = centroid_box(pts, Eigen::Vector3d(4.2, 1.5, 1.8));
    CHECK((c.centre_m - centre).norm() < 1e-6);
    CHECK(c.L_m == 4.2);
    CHECK(c.H_m == 1.5);
    CHECK(c.W_m == 1.8);
}

TEST_CASE("angles are wrapped to one turn from -pi up to but not including pi", "[boxes]") {
    CHECK(wrap_angle(kPi) == Approx(-kPi));
    CHECK(wrap_angle(-kPi) == Approx(-kPi));
    CHECK(wrap_angle(3.0 * kPi / 2.0) == Approx(-kPi / 2.0));
    CHECK(wrap_angle(-3.0 * kPi / 2.0) == Approx(kPi / 2.0));
    CHECK(wrap_angle(0.5) == Approx(0.5));
}

TEST_CASE("an imposed heading replaces the L-shape search and is validated", "[boxes]") {
    // A 4 m x 1 m strip of points along z: the L-shape search heads along z, the imposed yaw
    // (heading along x) makes the 4 m side the width.
    std::vector<Eigen::Vector3f> pts;
    for (float z = 10.0f; z <= 14.0f; z += 0.05f) {
        for (float x = 2.0f; x <= 3.0f; x += 0.05f) pts.emplace_back(x, 1.0f, z);
    }
    BoxFitOptions options;
    options.trim_fraction = 0.0;  // extents are the full point spans
    const OrientedBox searched = fit_upright_box(pts, std::nullopt, options);
    CHECK(searched.theta == Approx(-kPi / 2.0).margin(0.02));
    options.yaw_rad = 0.0;
    const OrientedBox imposed = fit_upright_box(pts, std::nullopt, options);
    CHECK(std::abs(std::sin(imposed.theta)) < 0.02);
    CHECK(imposed.L_m == Approx(1.0).margin(0.1));
    CHECK(imposed.W_m == Approx(4.0).margin(0.1));
    options.yaw_rad = std::nan("");
    CHECK_THROWS_WITH(options.validate(), Catch::Contains("yaw_rad"));
}

namespace {

/// Points of a vertical face from (x0, z0) to (x1, z1), heights 0.3-1.5 m above y = 1.65,
/// every step_m along it and 0.1 m up.
void add_face(std::vector<Eigen::Vector3f>& pts, double x0, double z0, double x1, double z1,
              double step_m) {
    const double length = std::hypot(x1 - x0, z1 - z0);
    for (double a = 0.0; a <= length + 1e-9; a += step_m) {
        for (double h = 0.3; h <= 1.5 + 1e-9; h += 0.1) {
            const double f = a / length;
            pts.emplace_back(x0 + f * (x1 - x0), 1.65 - h, z0 + f * (z1 - z0));
        }
    }
}

}  // namespace

TEST_CASE("a crossing car's side seen across the ray is its length despite stray points",
          "[boxes]") {
    // The side of a car crossing 26 m ahead (heading along x), its left part hidden by a nearer
    // car: 2.6 m seen (x -2.05..0.6). Beside it, 1 m of the nearer car's side running along the
    // ray and a sparse band of smear behind the face: the L-shape criterion settles on the
    // stray points and calls the length the ray's direction.
    std::vector<Eigen::Vector3f> pts;
    add_face(pts, -2.05, 25.7, 0.6, 25.7, 0.02);
    add_face(pts, -1.8, 24.5, -1.8, 25.5, 0.05);
    for (double z = 26.0; z <= 28.4 + 1e-9; z += 0.3) add_face(pts, -1.0, z, 0.0, z, 0.25);
    BoxFitOptions o;
    o.prior_L_m = 4.2;
    o.prior_W_m = 1.8;
    const OrientedBox box = fit_upright_box(pts, flat_ground(1.65), o);
    CHECK(yaw_error_mod_pi(box.theta, 0.0) < 5.0 * kPi / 180.0);
    CHECK(box.L_m == Approx(4.2).margin(0.05));
    // The hidden end is unknown: the seen face is completed on both ends alike.
    CHECK(box.centre_m.x() == Approx(-0.72).margin(0.15));
    o.face_share = 0.0;  // off: the closeness criterion alone
    CHECK(yaw_error_mod_pi(fit_upright_box(pts, flat_ground(1.65), o).theta, 0.0) >
          30.0 * kPi / 180.0);
    o.face_share = 1.5;
    CHECK_THROWS_WITH(o.validate(), Catch::Contains("face_share"));
}

TEST_CASE("range smear lined up along the viewing ray is not taken for a long side", "[boxes]") {
    // 0.35 m of the rear of a car 40 m ahead and to the left, each point displaced along its
    // viewing ray over 4 m: a straight band along the ray holding every point.
    std::vector<Eigen::Vector3f> pts;
    int k = 0;
    for (double x = -10.2; x <= -9.85 + 1e-9; x += 0.01) {
        for (double y = 0.3; y <= 1.6 + 1e-9; y += 0.1) {
            const Eigen::Vector3d p(x, y, 40.0);
            const double smear = 2.0 * std::sin(12.9898 * k++);
            pts.push_back((p * (1.0 + smear / p.norm())).cast<float>());
        }
    }
    BoxFitOptions o;
    o.prior_L_m = 4.2;
    o.prior_W_m = 1.8;
    const OrientedBox box = fit_upright_box(pts, flat_ground(1.65), o);
    // The band is no face: the fit is the closeness criterion's, exactly as with the face
    // test off (taken for a face, it would turn the heading onto the band's principal axis).
    o.face_share = 0.0;
    CHECK(box.theta == Approx(fit_upright_box(pts, flat_ground(1.65), o).theta));
}

TEST_CASE("a near car's side along the viewing ray is its length where smear is small", "[boxes]") {
    // A rendered car parked 5 m ahead on the right (centre x 5.0, z 5.4, heading along z), cut
    // by the image's right edge (tests/data/near-car-side.xyz): its left side runs 35 degrees
    // from the viewing ray, and the closeness criterion alone tilts the box by 15 degrees.
    std::ifstream in(std::string(STEREOSCENE_TEST_DATA_DIR) + "/near-car-side.xyz");
    std::vector<Eigen::Vector3f> pts;
    std::string line;
    while (std::getline(in, line)) {
        if (line.empty() || line[0] == '#') continue;
        std::istringstream fields(line);
        float x = 0, y = 0, z = 0;
        fields >> x >> y >> z;
        pts.emplace_back(x, y, z);
    }
    REQUIRE(pts.size() > 1000);
    BoxFitOptions o;
    o.prior_L_m = 4.2;
    o.prior_W_m = 1.8;
    o.truncation_xz = Eigen::Vector2d(4.3, 4.9);  // the points in the image's last columns
    const OrientedBox tilted = fit_upright_box(pts, flat_ground(1.65), o);
    CHECK(yaw_error_mod_pi(tilted.theta, -kPi / 2.0) > 10.0 * kPi / 180.0);
    // KITTI's rig: a pixel of disparity moves the side's far end (7.6 m) by 0.15 m, under a
    // tenth of its length: the side is a face.
    o.disparity_fb_px_m = 389.6;
    const OrientedBox box = fit_upright_box(pts, flat_ground(1.65), o);
    CHECK(yaw_error_mod_pi(box.theta, -kPi / 2.0) < 5.0 * kPi / 180.0);
    CHECK(box.centre_m.x() == Approx(5.0).margin(0.1));
    CHECK(box.centre_m.z() == Approx(5.4).margin(0.2));
    // The same points 20 m farther: a pixel moves the far end by 2 m, no face, as without the
    // rig.
    std::vector<Eigen::Vector3f> far;
    for (const auto& p : pts) far.emplace_back(p.x(), p.y(), p.z() + 20.0f);
    BoxFitOptions unknown = o;
    unknown.disparity_fb_px_m = 0.0;
    unknown.truncation_xz.reset();
    o.truncation_xz.reset();
    CHECK(fit_upright_box(far, flat_ground(1.65), o).theta ==
          Approx(fit_upright_box(far, flat_ground(1.65), unknown).theta));
    o.disparity_fb_px_m = -1.0;
    CHECK_THROWS_WITH(o.validate(), Catch::Contains("disparity_fb_px_m"));
}

TEST_CASE("a weighted fit to voxel centroids gives the box of the points", "[boxes]") {
    for (double t : {0.0, -0.3, -1.2, -kPi / 2.0, -2.5}) {
        const auto pts = box_faces(-3.0, 15.0, t, 12.0, 5.0, 3.0, 1.65, false);
        const VoxelGrid voxels = voxelize(pts, 0.4);
        std::vector<float> counts(voxels.count.begin(), voxels.count.end());
        BoxFitOptions o;
        o.rest_on_ground = false;
        const OrientedBox box =
            fit_upright_box_weighted(voxels.centroid_m, counts, flat_ground(1.65), o);
        INFO("true yaw " << t << ", fitted " << box.theta);
        CHECK(yaw_error_mod_pi(box.theta, t) < 0.03);
        // Centroids lie inside their voxels: extents within a voxel of the points'.
        CHECK(box.L_m == Approx(12.0).margin(0.4));
        CHECK(box.W_m == Approx(5.0).margin(0.4));
        CHECK(box.H_m == Approx(3.0).margin(0.4));
        CHECK(box.centre_m.x() == Approx(-3.0).margin(0.2));
        CHECK(box.centre_m.y() == Approx(1.65 - 1.5).margin(0.2));
        CHECK(box.centre_m.z() == Approx(15.0).margin(0.2));
    }
}

TEST_CASE("a point of weight k counts as k copies of it in the weighted fit", "[boxes]") {
    // Naive reference: the same points written out k times with weight 1.
    std::mt19937 rng(7);
    std::uniform_real_distribution<float> x(-4.0f, 4.0f), y(-2.0f, 1.5f), z(8.0f, 20.0f);
    std::uniform_int_distribution<int> k(1, 5);
    for (int trial = 0; trial < 5; ++trial) {
        std::vector<Eigen::Vector3f> pts, copies;
        std::vector<float> weights;
        for (int i = 0; i < 200; ++i) {
            pts.emplace_back(x(rng), y(rng), z(rng));
            weights.push_back(static_cast<float>(k(rng)));
            for (int c = 0; c < static_cast<int>(weights.back()); ++c) copies.push_back(pts.back());
        }
        const std::vector<float> ones(copies.size(), 1.0f);
        BoxFitOptions o;
        o.rest_on_ground = false;
        const OrientedBox a = fit_upright_box_weighted(pts, weights, flat_ground(1.65), o);
        const OrientedBox b = fit_upright_box_weighted(copies, ones, flat_ground(1.65), o);
        CHECK(a.theta == Approx(b.theta).margin(1e-6));
        CHECK(a.L_m == Approx(b.L_m).margin(1e-6));
        CHECK(a.W_m == Approx(b.W_m).margin(1e-6));
        CHECK(a.H_m == Approx(b.H_m).margin(1e-6));
        CHECK((a.centre_m - b.centre_m).norm() < 1e-6);
    }
}

TEST_CASE("weighted fit: extents are the 2/98 % quantiles of the points stood for", "[boxes]") {
    // Five points on a line along x at z 10 standing for 100 points; the 2 % and 98 %
    // quantiles are the points of ranks 2 and 97 written out.
    std::vector<Eigen::Vector3f> pts = {{1.0f, -1.0f, 10.0f},
                                        {2.0f, -1.0f, 10.0f},
                                        {3.0f, -1.0f, 10.0f},
                                        {4.0f, -1.0f, 10.0f},
                                        {5.0f, -1.0f, 10.0f}};
    BoxFitOptions o;
    o.rest_on_ground = false;
    o.yaw_rad = 0.0;  // heading along x
    const OrientedBox narrow = fit_upright_box_weighted(pts, {1, 1, 96, 1, 1}, std::nullopt, o);
    CHECK(narrow.centre_m.x() == Approx(3.0).margin(1e-9));
    CHECK(narrow.L_m == Approx(o.min_extent_m).margin(1e-9));
    // Written out: 1 1 2 (48 times) 3 4 (47 times) 5 5: ranks 2 and 97 are 2 and 4.
    const OrientedBox wide = fit_upright_box_weighted(pts, {2, 48, 1, 47, 2}, std::nullopt, o);
    CHECK(wide.centre_m.x() == Approx(3.0).margin(1e-9));
    CHECK(wide.L_m == Approx(2.0).margin(1e-9));
}

TEST_CASE("the weighted fit rejects weights that are missing or not positive", "[boxes]") {
    const std::vector<Eigen::Vector3f> pts = {{0.0f, 0.0f, 10.0f}, {1.0f, 0.0f, 10.0f}};
    CHECK_THROWS_WITH(fit_upright_box_weighted(pts, {1.0f}, std::nullopt, BoxFitOptions{}),
                      Catch::Contains("weights"));
    CHECK_THROWS_WITH(fit_upright_box_weighted(pts, {1.0f, 0.0f}, std::nullopt, BoxFitOptions{}),
                      Catch::Contains("weights"));
}

TEST_CASE("a dense noisy car over the angle search's point limit gives its heading in any order",
          "[boxes]") {
    // The thesis's test car: 12 m ahead, right of the camera, heading along +z; its rear and
    // left side visible, dense (over the angle search's 3000-point limit), with range noise.
    auto pts = box_faces(1.8, 12.0, -kPi / 2.0, 4.2, 1.8, 1.5, 1.65, true);
    std::mt19937 rng(7);
    std::normal_distribution<float> noise(0.0f, 0.08f);
    for (auto& p : pts) p *= 1.0f + noise(rng) / p.norm();
    REQUIRE(pts.size() > 3000);
    BoxFitOptions o;
    o.prior_L_m = 4.2;
    o.prior_W_m = 1.8;
    o.prior_H_m = 1.5;
    const OrientedBox first = fit_upright_box(pts, flat_ground(1.65), o);
    CHECK(yaw_error_mod_pi(first.theta, -kPi / 2.0) < 3.0 * kPi / 180.0);
    for (unsigned seed : {1u, 2u, 3u}) {
        std::shuffle(pts.begin(), pts.end(), std::mt19937(seed));
        const OrientedBox box = fit_upright_box(pts, flat_ground(1.65), o);
        CHECK(yaw_error_mod_pi(box.theta, first.theta) < 1e-6);
    }
}

namespace {

/// The faces turned to the camera of a 4.5 x 1.8 x 1.5 m car heading +z at (x, z), left of the
/// image's right edge (40 degrees off the axis) and nearer than max_z.
std::vector<Eigen::Vector3f> left_of_right_edge(double x, double z, double max_z) {
    std::vector<Eigen::Vector3f> seen;
    for (const auto& p : box_faces(x, z, -kPi / 2.0, 4.5, 1.8, 1.5, 1.65, true)) {
        if (static_cast<double>(p.x() / p.z()) < kRightEdge && double{p.z()} < max_z) {
            seen.push_back(p);
        }
    }
    return seen;
}

/// The car priors of those tests, cut by the right edge at lateral offset x_cut.
BoxFitOptions cut_at_right_edge(double x_cut) {
    BoxFitOptions o;
    o.prior_L_m = 4.5;
    o.prior_W_m = 1.8;
    o.truncation_xz = Eigen::Vector2d(x_cut, x_cut / kRightEdge);
    return o;
}

}  // namespace

TEST_CASE("a car ahead whose rear the image edge only clips is completed away from the camera",
          "[boxes]") {
    // Ahead on the right, heading +z, its rear at z 4.75 seen whole but for the far corner
    // beyond the image's right edge, and 2 m of its left side (the rest hidden). Completed
    // beyond the edge, its 4.5 m would run 2.5 m in front of the rear, over ground the camera
    // sees: more than a quarter of that part lies in view.
    const auto seen = left_of_right_edge(3.3, 7.0, 6.75);
    REQUIRE(seen.size() > 100);
    const OrientedBox box = fit_upright_box(seen, flat_ground(1.65), cut_at_right_edge(3.95));
    CHECK(yaw_error_mod_pi(box.theta, -kPi / 2.0) < 0.05);
    CHECK(box.centre_m.z() == Approx(7.0).margin(0.2));
    CHECK(box.centre_m.x() == Approx(3.3).margin(0.2));
}

TEST_CASE("a car cut by the image edge is completed beyond the edge, not along the edge's ray",
          "[boxes]") {
    // Parked on the right, heading +z, 5 m ahead: the image's right edge cuts its left side at
    // z 4.9, so only 2.4 m of that side is seen.
    const auto seen = left_of_right_edge(5.0, 5.0, 100.0);
    REQUIRE(seen.size() > 100);
    BoxFitOptions o = cut_at_right_edge(4.1);
    const OrientedBox box = fit_upright_box(seen, flat_ground(1.65), o);
    CHECK(yaw_error_mod_pi(box.theta, -kPi / 2.0) < 0.05);
    CHECK(box.centre_m.z() == Approx(5.0).margin(0.2));
    CHECK(box.centre_m.x() == Approx(5.0).margin(0.2));
    // Without the cut, the prior completes the seen side away from the camera.
    o.truncation_xz.reset();
    CHECK(fit_upright_box(seen, flat_ground(1.65), o).centre_m.z() > 6.5);
}

TEST_CASE("with_length keeps the end nearer the camera or the farther one in place", "[boxes]") {
    OrientedBox box;
    box.theta = -kPi / 2.0;  // heading +z
    box.L_m = 6.0;
    box.W_m = 2.0;
    box.centre_m = Eigen::Vector3d(-4.0, 0.9, 20.0);  // ends at z 17 and 23
    const OrientedBox near_kept = with_length(box, 5.2, false);
    CHECK(near_kept.L_m == 5.2);
    CHECK(near_kept.centre_m.z() - near_kept.L_m / 2.0 == Approx(17.0).margin(1e-9));
    CHECK(near_kept.centre_m.x() == Approx(-4.0).margin(1e-9));
    const OrientedBox far_kept = with_length(box, 5.2, true);
    CHECK(far_kept.centre_m.z() + far_kept.L_m / 2.0 == Approx(23.0).margin(1e-9));
    // The same box heading the other way (towards the camera) keeps the same ends.
    box.theta = kPi / 2.0;
    CHECK(with_length(box, 5.2, true).centre_m.z() == Approx(far_kept.centre_m.z()).margin(1e-9));
    CHECK(with_length(box, 7.0, false).centre_m.z() == Approx(20.5).margin(1e-9));
    CHECK(with_length(box, 6.0, true).centre_m == box.centre_m);
}

TEST_CASE("a thing cut by something in front of it shares its missing length between both ends",
          "[boxes]") {
    // The left side of a car parked on the right (x = 3), seen from z = 9 to 12.6: 3.6 m of a
    // 4.4 m prior, 0.8 m missing.
    std::vector<Eigen::Vector3f> pts;
    for (float y = 0.3f; y <= 1.5f; y += 0.05f) {
        for (float z = 9.0f; z <= 12.6f; z += 0.05f) pts.emplace_back(3.0f, y, z);
        for (float x = 3.0f; x <= 4.8f; x += 0.05f) pts.emplace_back(x, y, 12.6f);
    }
    BoxFitOptions o;
    o.prior_L_m = 4.4;
    o.prior_W_m = 1.8;
    // No cut: the hidden part lies away from the camera, the near end stays.
    const OrientedBox away = fit_upright_box(pts, flat_ground(1.65), o);
    CHECK(away.L_m == Approx(4.4).margin(0.05));
    CHECK(away.centre_m.z() == Approx(9.0 + 2.2).margin(0.15));
    // Something nearer stands right of the near end in the image (an occluder's cut, side +1;
    // the near end of a thing on the right lies further right): half the missing length goes
    // beyond the cut, towards the camera.
    o.truncation_xz = Eigen::Vector2d(3.0, 9.0);
    o.truncation_side = 1;
    const OrientedBox cut = fit_upright_box(pts, flat_ground(1.65), o);
    CHECK(cut.L_m == Approx(away.L_m).margin(0.01));
    CHECK(cut.centre_m.z() == Approx(away.centre_m.z() - 0.4).margin(0.05));
    CHECK(yaw_error_mod_pi(cut.theta, away.theta) < 1e-6);
    // The same cut at the image's edge (side 0): all of it beyond the cut, none away.
    o.truncation_side = 0;
    CHECK(fit_upright_box(pts, flat_ground(1.65), o).centre_m.z() ==
          Approx(away.centre_m.z() - 0.8).margin(0.1));
    o.truncation_side = 2;
    CHECK_THROWS_WITH(o.validate(), Catch::Contains("truncation_side"));
}
