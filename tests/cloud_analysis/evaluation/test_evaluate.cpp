#include <cmath>
#include <filesystem>

#include <catch2/catch.hpp>
#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>

#include "cloud_analysis/evaluation/evaluate.hpp"
#include "cloud_analysis/stereo/calibration.hpp"
#include "stereoscene/support/angles.hpp"

using namespace cloud_analysis;

namespace {

using stereoscene::support::kPi;

scene_schema::Entity car_entity(double x, double z, double theta, double L = 4.2, double W = 1.8) {
    scene_schema::Entity e;
    e.id = "car-x";
    e.class_name = "car";
    e.class_id = 26;
    e.x = x;
    e.y = 0.9;
    e.z = z;
    e.theta = theta;
    e.L = L;
    e.W = W;
    e.H = 1.5;
    return e;
}

/// A GT car: n points spread along z over [z - 2, z + 2] at x, on its visible side.
GtCar gt_car(int instance, double x, double z, std::size_t n) {
    GtCar car;
    car.instance = instance;
    for (std::size_t i = 0; i < n; ++i) {
        const double t = n > 1 ? static_cast<double>(i) / static_cast<double>(n - 1) : 0.5;
        car.points_m.emplace_back(x, 1.0, z - 2.0 + 4.0 * t);
    }
    car.pixel_count = n;
    car.centroid_m = Eigen::Vector3d(x, 1.0, z);
    return car;
}

}  // namespace

TEST_CASE("the footprint test uses the KITTI heading and the margin", "[evaluate]") {
    // Heading along +z (theta = -pi/2): L runs along z, W along x.
    const auto e = car_entity(0.0, 10.0, -kPi / 2.0);
    const std::vector<Eigen::Vector3f> pts = {{0.0f, 1.0f, 11.9f},   // inside
                                              {0.0f, 1.0f, 12.3f},   // inside only with margin
                                              {1.0f, 1.0f, 10.0f},   // inside only with margin
                                              {0.0f, 1.0f, 12.6f},   // outside
                                              {1.4f, 1.0f, 10.0f}};  // outside
    CHECK(footprint_inside_fraction(e, pts, 0.0) == Approx(1.0 / 5.0));
    CHECK(footprint_inside_fraction(e, pts, 0.3) == Approx(3.0 / 5.0));
    // The same car turned to heading +x (theta = 0): now 11.9 is outside, x = 1.4 inside.
    const auto turned = car_entity(0.0, 10.0, 0.0);
    CHECK(footprint_inside_fraction(turned, {{1.4f, 1.0f, 10.0f}}, 0.0) == 1.0);
    CHECK(footprint_inside_fraction(turned, {{0.0f, 1.0f, 11.9f}}, 0.3) == 0.0);
}

TEST_CASE("matching: half the points inside matches, an offset box does not", "[evaluate]") {
    const std::vector<GtCar> gt = {gt_car(1, -4.0, 12.0, 400)};
    CarMatchOptions o;
    // Box shifted 2 m along z: 2.3 m of the 4 m point run (grown by 0.3 m) is inside: 57 %.
    auto ev = evaluate_cars({car_entity(-4.0, 14.0, -kPi / 2.0)}, gt, o);
    CHECK(ev.recall() == 1.0);
    CHECK(ev.precision() == 1.0);
    REQUIRE(ev.matches.size() == 1);
    CHECK(ev.matches[0].centre_distance_m == Approx(2.0));
    // Shifted 3 m: 1.3 / 4 = 33 % inside, no match.
    ev = evaluate_cars({car_entity(-4.0, 15.0, -kPi / 2.0)}, gt, o);
    CHECK(ev.gt_owed == 1);
    CHECK(ev.gt_owed_matched == 0);
    CHECK(ev.entities_in_range == 1);
    CHECK(ev.entities_matched == 0);
}

TEST_CASE("matching: one box over a whole parked row is not a car", "[evaluate]") {
    const std::vector<GtCar> gt = {gt_car(1, -4.0, 12.0, 400), gt_car(2, -4.0, 17.0, 400)};
    // 10 m x 1.8 m grown by 0.3 m: 10.6 * 2.4 = 25.4 m^2 > 20 m^2.
    const auto ev =
        evaluate_cars({car_entity(-4.0, 14.5, -kPi / 2.0, 10.0)}, gt, CarMatchOptions{});
    CHECK(ev.gt_owed_matched == 0);
    CHECK(ev.entities_matched == 0);
}

TEST_CASE("matching is one-to-one, range-limited, and small GT cars only count for precision",
          "[evaluate]") {
    const std::vector<GtCar> gt = {gt_car(1, -4.0, 12.0, 400),  // owed
                                   gt_car(2, 4.0, 20.0, 150),   // too few pixels: not owed
                                   gt_car(3, 4.0, 45.0, 900)};  // beyond 30 m: not owed
    const std::vector<scene_schema::Entity> entities = {
        car_entity(-4.0, 12.0, -kPi / 2.0),  // matches GT 1
        car_entity(-4.0, 12.2, -kPi / 2.0),  // duplicate on GT 1: unmatched
        car_entity(4.0, 20.0, -kPi / 2.0),   // matches GT 2 (counts for precision)
        car_entity(4.0, 45.0, -kPi / 2.0)};  // out of range: ignored
    const auto ev = evaluate_cars(entities, gt, CarMatchOptions{});
    CHECK(ev.gt_owed == 1);
    CHECK(ev.gt_owed_matched == 1);
    CHECK(ev.entities_in_range == 3);
    CHECK(ev.entities_matched == 2);
    CHECK(ev.precision() == Approx(2.0 / 3.0));
    CHECK(ev.matches.size() == 3);  // the far pair still matches, it just is not counted
}

TEST_CASE("GT cars come from the instance image's car ids and the GT disparity", "[evaluate]") {
    const auto dir = std::filesystem::temp_directory_path() / "stereoscene_test_evaluate";
    std::filesystem::create_directories(dir);
    cv::Mat instance(4, 6, CV_16UC1, cv::Scalar(0));
    cv::Mat disparity(4, 6, CV_16UC1, cv::Scalar(0));
    // Car instance 3 (26 << 8 | 3) on columns 0-1, a person (24 << 8 | 1) on column 5.
    for (int v = 0; v < 4; ++v) {
        instance.at<std::uint16_t>(v, 0) = (26 << 8) | 3;
        instance.at<std::uint16_t>(v, 1) = (26 << 8) | 3;
        instance.at<std::uint16_t>(v, 5) = (24 << 8) | 1;
        disparity.at<std::uint16_t>(v, 0) = 10 * 256;
        disparity.at<std::uint16_t>(v, 5) = 10 * 256;
    }
    REQUIRE(cv::imwrite((dir / "instance.png").string(), instance));
    REQUIRE(cv::imwrite((dir / "disp.png").string(), disparity));
    StereoCamera cam;
    cam.fx_px = cam.fy_px = 500.0;
    cam.cx_px = cam.cx_right_px = 3.0;
    cam.cy_px = 2.0;
    cam.baseline_m = 0.5;
    const auto cars = load_gt_cars(dir / "instance.png", dir / "disp.png", cam);
    REQUIRE(cars.size() == 1);
    CHECK(cars[0].instance == 3);
    CHECK(cars[0].pixel_count == 4);  // column 1 has no disparity
    // z = f B / d = 500 * 0.5 / 10 = 25 m; x = (0 - 3) * 25 / 500 = -0.15 m.
    CHECK(cars[0].centroid_m.z() == Approx(25.0));
    CHECK(cars[0].centroid_m.x() == Approx(-0.15));
    CHECK_THROWS_WITH(load_gt_cars(dir / "missing.png", dir / "disp.png", cam),
                      Catch::Contains("missing.png"));
    std::filesystem::remove_all(dir);
}

TEST_CASE("an unmatched entity on a GT car without GT disparity is unscorable, not wrong",
          "[evaluate]") {
    StereoCamera cam;
    cam.fx_px = cam.fy_px = 500.0;
    cam.cx_px = cam.cx_right_px = 50.0;
    cam.cy_px = 20.0;
    cam.baseline_m = 0.5;
    // GT car 7 covers pixels u 40..60, v 15..25 of a 100 x 40 image but has no GT points.
    GtCar blind;
    blind.instance = 7;
    blind.image_width_px = 100;
    for (int v = 15; v <= 25; ++v) {
        for (int u = 40; u <= 60; ++u)
            blind.image_pixels.push_back(static_cast<std::uint32_t>(v * 100 + u));
    }
    const std::vector<GtCar> gt = {gt_car(1, -4.0, 12.0, 400), blind};
    // Entity centre (0, 0.9, 10) projects to u = 50, v = 65: below the blind car.
    auto off = car_entity(0.0, 10.0, -kPi / 2.0);
    // Entity centre (0, 0, 10) projects to u = 50, v = 20: on the blind car.
    auto on = car_entity(0.0, 10.0, -kPi / 2.0);
    on.y = 0.0;
    const std::vector<scene_schema::Entity> entities = {car_entity(-4.0, 12.0, -kPi / 2.0), on,
                                                        off};
    const auto ev = evaluate_cars(entities, gt, CarMatchOptions{}, &cam);
    CHECK(ev.entities_in_range == 3);
    CHECK(ev.entities_matched == 1);
    CHECK(ev.entities_unscorable == 1);
    CHECK(ev.precision() == Approx(1.0 / 3.0));
    CHECK(ev.precision_scorable() == Approx(1.0 / 2.0));
    // Without a camera nothing is unscorable.
    CHECK(evaluate_cars(entities, gt, CarMatchOptions{}).entities_unscorable == 0);
}

TEST_CASE("a car's own surface is the depth group with the most points inside its mask",
          "[evaluate]") {
    GtCarOptions o;  // gap 1.5 m
    // Five points of a van in front on the mask's border strip, three inside on the car.
    const std::vector<GtDepth> occluded = {{10.0f, false}, {19.0f, true}, {10.2f, false},
                                           {10.4f, true},  {19.5f, true}, {10.3f, false},
                                           {20.3f, true},  {10.1f, false}};
    CHECK(own_surface_min_depth_m(occluded, o) == 19.0f);
    // Background bleed behind is on the border too: the car stays at 20 m.
    CHECK(own_surface_min_depth_m(
              {{20.0f, true}, {20.3f, true}, {45.0f, false}, {45.2f, false}, {45.4f, false}}, o) ==
          20.0f);
    // Depths closer than the gap are one surface (a car seen along its length).
    CHECK(own_surface_min_depth_m({{12.0f, true}, {13.4f, false}, {14.8f, true}, {16.2f, false}},
                                  o) == 12.0f);
    // A mask too thin for interior points: the largest group.
    CHECK(own_surface_min_depth_m({{30.0f, false}, {40.0f, false}, {40.5f, false}}, o) == 40.0f);
    // Gap 0 is the old rule: keep every point.
    o.occluder_gap_m = 0.0;
    CHECK(own_surface_min_depth_m(occluded, o) == 0.0f);
    CHECK(own_surface_min_depth_m({}, GtCarOptions{}) == 0.0f);
    o.min_interior_px = 0;
    CHECK_THROWS_WITH(o.validate(), Catch::Contains("min_interior_px"));
}

TEST_CASE("border distance is the chessboard distance to another label, not to the image edge",
          "[evaluate]") {
    // 6 x 3: label 1 on columns 0-4, label 2 on column 5.
    const std::vector<std::uint16_t> labels = {1, 1, 1, 1, 1, 2,  //
                                               1, 1, 1, 1, 1, 2,  //
                                               1, 1, 1, 1, 1, 2};
    const std::vector<int> d = label_border_distance_px(labels, 6, 3);
    const std::vector<int> row = {5, 4, 3, 2, 1, 1};
    for (int v = 0; v < 3; ++v) {
        for (int u = 0; u < 6; ++u) CHECK(d[static_cast<std::size_t>(v * 6 + u)] == row[u]);
    }
    // A diagonal neighbour counts as 1 (8-neighbourhood).
    const std::vector<int> diag = label_border_distance_px({1, 1, 1, 2}, 2, 2);
    CHECK(diag == std::vector<int>{1, 1, 1, 1});
}

TEST_CASE("GT car pixels on a nearer occluder at the mask border are dropped and counted",
          "[evaluate]") {
    const auto dir = std::filesystem::temp_directory_path() / "stereoscene_test_evaluate_occl";
    std::filesystem::create_directories(dir);
    // Car 2 on columns 0-9 of a 12 x 10 image, the van (car 9) in front on columns 10-11. The
    // car's mask bleeds over the van on columns 8-9: 20 GT pixels at the van's 10 m. The car's
    // own surface has sparse GT, 12 pixels at 20 m inside the mask (rows 0 and 5, columns 0-5).
    cv::Mat instance(10, 12, CV_16UC1, cv::Scalar((26 << 8) | 2));
    cv::Mat disparity(10, 12, CV_16UC1, cv::Scalar(0));
    StereoCamera cam;
    cam.fx_px = cam.fy_px = 500.0;
    cam.cx_px = cam.cx_right_px = 6.0;
    cam.cy_px = 5.0;
    cam.baseline_m = 0.5;
    for (int v = 0; v < 10; ++v) {
        for (int u = 10; u < 12; ++u) instance.at<std::uint16_t>(v, u) = (26 << 8) | 9;
        for (int u = 8; u < 12; ++u) disparity.at<std::uint16_t>(v, u) = 25 * 256;  // 10 m
    }
    for (int v : {0, 5}) {
        for (int u = 0; u < 6; ++u) disparity.at<std::uint16_t>(v, u) = 3200;  // 12.5 px: 20 m
    }
    REQUIRE(cv::imwrite((dir / "instance.png").string(), instance));
    REQUIRE(cv::imwrite((dir / "disp.png").string(), disparity));
    auto cars = load_gt_cars(dir / "instance.png", dir / "disp.png", cam);
    REQUIRE(cars.size() == 2);
    CHECK(cars[0].instance == 2);
    CHECK(cars[0].pixel_count == 12);
    CHECK(cars[0].occluder_pixel_count == 20);
    CHECK(cars[0].centroid_m.z() == Approx(20.0));
    CHECK(cars[0].mask_box_px == Eigen::Vector4d(0, 0, 10, 10));
    CHECK(cars[1].pixel_count == 20);  // the van keeps its own pixels
    CHECK(cars[1].occluder_pixel_count == 0);
    GtCarOptions keep_all;
    keep_all.occluder_gap_m = 0.0;
    cars = load_gt_cars(dir / "instance.png", dir / "disp.png", cam, keep_all);
    CHECK(cars[0].pixel_count == 32);
    CHECK(cars[0].occluder_pixel_count == 0);
    std::filesystem::remove_all(dir);
}

TEST_CASE("a box projects to the rectangle of its eight corners, clipped to the image",
          "[evaluate]") {
    StereoCamera cam;
    cam.fx_px = cam.fy_px = 500.0;
    cam.cx_px = 200.0;
    cam.cy_px = 100.0;
    // 4.2 m along z from 17.9 to 22.1 m, 1.8 m wide, 1.5 m high, centred on the optical axis:
    // the near face spans u = 200 +- 500 * 0.9 / 17.9, v = 100 +- 500 * 0.75 / 17.9 (+ 0.5).
    auto e = car_entity(0.0, 20.0, -kPi / 2.0);
    e.y = 0.0;
    const auto box = projected_box_px(e, cam, 400, 200);
    REQUIRE(box);
    CHECK((*box)[0] == Approx(200.5 - 450.0 / 17.9));
    CHECK((*box)[2] == Approx(200.5 + 450.0 / 17.9));
    CHECK((*box)[1] == Approx(100.5 - 375.0 / 17.9));
    CHECK((*box)[3] == Approx(100.5 + 375.0 / 17.9));
    // Clipped at the image border; a box reaching behind the camera has no rectangle.
    CHECK((*projected_box_px(e, cam, 210, 200))[2] == 210.0);
    e.z = 1.0;
    CHECK_FALSE(projected_box_px(e, cam, 400, 200));
    CHECK(rect_iou({0, 0, 10, 10}, {5, 0, 15, 10}) == Approx(50.0 / 150.0));
    CHECK(rect_iou({0, 0, 10, 10}, {20, 0, 30, 10}) == 0.0);
    CHECK(rect_iou({0, 0, 10, 10}, {0, 0, 10, 10}) == 1.0);
}

TEST_CASE("an entity on a GT car without GT points matches by KITTI's 2D criterion", "[evaluate]") {
    StereoCamera cam;
    cam.fx_px = cam.fy_px = 500.0;
    cam.cx_px = cam.cx_right_px = 200.0;
    cam.cy_px = 100.0;
    cam.baseline_m = 0.5;
    // GT car 17: mask columns 175-225, rows 80-121 of a 400 x 200 image, no GT points.
    GtCar blind;
    blind.instance = 17;
    blind.image_width_px = 400;
    blind.image_height_px = 200;
    for (int v = 80; v <= 121; ++v) {
        for (int u = 175; u <= 225; ++u)
            blind.image_pixels.push_back(static_cast<std::uint32_t>(v * 400 + u));
    }
    blind.mask_box_px = Eigen::Vector4d(175, 80, 226, 122);
    const std::vector<GtCar> gt = {gt_car(1, -4.0, 12.0, 400), blind};
    auto on = car_entity(0.0, 20.0, -kPi / 2.0);  // projects onto the mask rectangle
    on.y = 0.0;
    auto beside = on;  // 1.5 m to the right: IoU about 0.1
    beside.x = 1.5;
    auto row = on;  // on it, but 10 m long: a parked row, not a car
    row.L = 10.0;
    const std::vector<scene_schema::Entity> entities = {car_entity(-4.0, 12.0, -kPi / 2.0), on, on,
                                                        beside, row};
    const auto ev = evaluate_cars(entities, gt, CarMatchOptions{}, &cam);
    REQUIRE(ev.matches.size() == 2);
    CHECK_FALSE(ev.matches[0].fallback);
    CHECK(ev.matches[1].fallback);
    CHECK(ev.matches[1].entity == 1);  // one entity per GT car: the duplicate stays unmatched
    CHECK(ev.matches[1].gt == 1);
    CHECK(ev.matches[1].iou_2d > 0.9);
    CHECK(ev.entities_matched == 2);
    CHECK(ev.fallback_matched == 1);
    CHECK(ev.entities_in_range == 5);
    // Without a camera the rule cannot project: only the footprint match remains.
    const auto no_camera = evaluate_cars(entities, gt, CarMatchOptions{});
    CHECK(no_camera.entities_matched == 1);
    CHECK(no_camera.fallback_matched == 0);
    // A GT car with more points than fallback_max_points is judged by its points only.
    CarMatchOptions strict;
    strict.fallback_max_points = 0;
    GtCar few = blind;
    few.points_m.assign(3, Eigen::Vector3f(9.0f, 1.0f, 30.0f));
    few.pixel_count = 3;
    few.centroid_m = Eigen::Vector3d(9.0, 1.0, 30.0);
    CHECK(evaluate_cars(entities, {few}, strict, &cam).entities_matched == 0);
    CHECK(evaluate_cars(entities, {few}, CarMatchOptions{}, &cam).fallback_matched == 1);
}

TEST_CASE("a ground-truth car's pixels that lie on a nearer car in front of it count as occluded",
          "[evaluate][kitti]") {
    const std::filesystem::path root =
        std::filesystem::path(STEREOSCENE_SHARED_DATA_DIR) / "kitti15";
    const StereoCamera cam = load_calibration(root / "calib/calib_cam_to_cam.txt").camera;
    const auto cars =
        load_gt_cars(root / "instance/000000_10.png", root / "disp_occ_0/000000_10.png", cam);
    const auto car = [&](int id) -> const GtCar& {
        for (const auto& c : cars) {
            if (c.instance == id) return c;
        }
        FAIL("no GT car " << id);
        return cars.front();
    };
    // Car 2: 444 GT pixels, 217 on the van (car 9) at 9.6-10.8 m and 50 at 13.7-16.5 m in
    // front of its own 177 at 18.4-27.1 m (docs/evaluation.md "Cars").
    CHECK(car(2).pixel_count == 177);
    CHECK(car(2).occluder_pixel_count == 267);
    CHECK(car(2).range_m() > 20.0);
    // The van itself and car 3 keep every pixel; car 17 has none and a mask rectangle.
    CHECK(car(9).occluder_pixel_count == 0);
    CHECK(car(3).occluder_pixel_count == 0);
    CHECK(car(17).pixel_count == 0);
    CHECK(car(17).mask_box_px == Eigen::Vector4d(904, 195, 1242, 375));
}
