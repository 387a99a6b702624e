#include <catch2/catch.hpp>

#include <cmath>
#include <filesystem>

#include "cloud_analysis/cloud/reproject.hpp"
#include "cloud_analysis/stereo/calibration.hpp"

using namespace cloud_analysis;

namespace {
const std::filesystem::path kShared = STEREOSCENE_SHARED_DATA_DIR;
}

TEST_CASE("KITTI raw calibration gives fx, cx and the 0.53 m baseline", "[calibration]") {
    const char* text =
        "calib_time: 09-Jan-2012 13:57:47\n"
        "S_rect_02: 1.242000e+03 3.750000e+02\n"
        "P_rect_02: 7.215377e+02 0 6.095593e+02 4.485728e+01 0 7.215377e+02 1.728540e+02 "
        "2.163791e-01 0 0 1 2.745884e-03\n"
        "P_rect_03: 7.215377e+02 0 6.095593e+02 -3.395242e+02 0 7.215377e+02 1.728540e+02 "
        "2.199936e+00 0 0 1 2.729905e-03\n";
    const Calibration c = parse_calibration(text, "raw.txt");
    CHECK(c.format == "kitti_raw");
    CHECK(c.camera.fx_px == Approx(721.5377));
    CHECK(c.camera.cx_px == Approx(609.5593));
    CHECK(c.camera.cy_px == Approx(172.854));
    CHECK(c.camera.baseline_m == Approx((44.85728 + 339.5242) / 721.5377));
    CHECK(c.camera.width_px == 1242);
    CHECK(c.camera.height_px == 375);
    CHECK_FALSE(c.raw_left.has_value());
}

TEST_CASE("kitti15's calibration without P_rect_03 derives the baseline from R and T",
          "[calibration][kitti]") {
    const Calibration c = load_calibration(kShared / "kitti15/calib/calib_cam_to_cam.txt");
    CHECK(c.camera.baseline_m == Approx(0.532).margin(0.003));
    CHECK_FALSE(c.note.empty());
    REQUIRE(c.raw_left.has_value());
    CHECK(c.raw_left->distortion.size() == 5);
}

TEST_CASE("KITTI object calibration reads P2 and P3", "[calibration][kitti]") {
    const Calibration c = load_calibration(kShared / "kitti_object/calib/000000.txt");
    CHECK(c.format == "kitti_object");
    CHECK(c.camera.fx_px == Approx(707.0493));
    CHECK(c.camera.baseline_m == Approx((45.75831 + 334.1081) / 707.0493));
}

TEST_CASE("YAML and JSON calibrations read the same rig", "[calibration]") {
    const Calibration y = parse_calibration(
        "# rig\nfx: 700\nfy: 700\ncx: 320\ncy: 240\nbaseline_m: 0.5\n"
        "distortion: [0.1, -0.01, 0, 0, 0]\n",
        "rig.yaml");
    const Calibration j = parse_calibration(
        R"({"fx": 700, "fy": 700, "cx": 320, "cy": 240, "baseline_m": 0.5})", "rig.json");
    CHECK(y.format == "yaml");
    CHECK(j.format == "json");
    CHECK(y.camera.baseline_m == j.camera.baseline_m);
    CHECK(y.camera.cx_right_px == Approx(320));
    REQUIRE(y.raw_left.has_value());
    CHECK(y.raw_left->distortion[0] == Approx(0.1));
    CHECK_FALSE(j.raw_left.has_value());
}

TEST_CASE("a calibration missing a field or with zero baseline names the field and file",
          "[calibration]") {
    REQUIRE_THROWS_WITH(parse_calibration("fx: 700\nfy: 700\ncx: 1\nbaseline_m: 0.5\n", "a.yaml"),
                        Catch::Contains("cy: missing") && Catch::Contains("(a.yaml)"));
    REQUIRE_THROWS_WITH(
        parse_calibration("fx: 700\nfy: 700\ncx: 1\ncy: 1\nbaseline_m: 0\n", "b.yaml"),
        Catch::Contains("baseline_m: must be > 0"));
    REQUIRE_THROWS_WITH(
        parse_calibration("P2: 1 0 0 0 0 1 0 0 0 0 1 0\nP3: 1 0 0 0 0 1 0 0 0 0 1 0\n", "c.txt"),
        Catch::Contains("baseline must be > 0"));
    REQUIRE_THROWS_WITH(parse_calibration("hello: world\n", "d.txt"), Catch::Contains("format"));
    REQUIRE_THROWS_WITH(load_calibration("/nonexistent/calib.txt"),
                        Catch::Contains("/nonexistent/calib.txt"));
}

TEST_CASE("Q reprojects a disparity plane to Z = f*B/d", "[calibration][reproject]") {
    StereoCamera cam;
    cam.fx_px = cam.fy_px = 721.5;
    cam.cx_px = cam.cx_right_px = 600.0;
    cam.cy_px = 170.0;
    cam.baseline_m = 0.54;
    cam.width_px = 40;
    cam.height_px = 20;
    const double d = 19.48;  // f * B / 20 m
    DisparityMap map{40, 20, std::vector<float>(800, static_cast<float>(d))};
    map.disparity_px[5] = kNoDisparity;
    ImageU8 grey{40, 20, 1, std::vector<std::uint8_t>(800, 128)};
    const LabeledCloud cloud = reproject(map, cam, grey, ClassImage{}, ReprojectOptions{});
    REQUIRE(cloud.size() == 799);
    for (std::size_t i = 0; i < cloud.size(); ++i) {
        const int u = static_cast<int>(cloud.pixel[i] % 40);
        const int v = static_cast<int>(cloud.pixel[i] / 40);
        const double z = cam.fx_px * cam.baseline_m / d;
        CHECK(cloud.xyz_m[i].z() == Approx(z).epsilon(1e-5));
        CHECK(cloud.xyz_m[i].x() == Approx((u - cam.cx_px) * z / cam.fx_px).epsilon(1e-5));
        CHECK(cloud.xyz_m[i].y() == Approx((v - cam.cy_px) * z / cam.fy_px).epsilon(1e-5));
        CHECK(cloud.class_index[i] == kVoidClass);
    }
    ReprojectOptions near;
    near.max_range_m = 10.0;  // every point is ~20 m away: none survives, none at z = 10000
    CHECK(reproject(map, cam, grey, ClassImage{}, near).size() == 0);
}

TEST_CASE("a disparity offset is added to every disparity before depth, raw cameras unchanged",
          "[calibration][reproject]") {
    const char* text =
        "fx: 700\nfy: 700\ncx: 320\ncy: 240\nbaseline_m: 0.5\ncx_right: 322\n"
        "distortion: [0.1, -0.01, 0, 0, 0]\n";
    CalibrationOptions options;
    options.disparity_offset_px = 0.5;
    const Calibration plain = parse_calibration(text, "rig.yaml");
    const Calibration shifted = parse_calibration(text, "rig.yaml", options);
    CHECK(shifted.camera.cx_right_px == Approx(322.5));
    // 10 px measured: 10 - (320 - 322) = 12 px as filed, 12.5 px with the offset.
    CHECK(match_border(plain.camera).depth_m(10.0) == Approx(350.0 / 12.0));
    CHECK(match_border(shifted.camera).depth_m(10.0) == Approx(350.0 / 12.5));
    REQUIRE(shifted.raw_right.has_value());
    CHECK(shifted.raw_right->K(0, 2) == Approx(322.0));

    const StereoCamera cam = shifted.camera;
    DisparityMap map{4, 2, std::vector<float>(8, 10.0f)};
    ImageU8 grey{4, 2, 1, std::vector<std::uint8_t>(8, 128)};
    const LabeledCloud cloud = reproject(map, cam, grey, ClassImage{}, ReprojectOptions{});
    REQUIRE(cloud.size() == 8);
    CHECK(cloud.xyz_m[0].z() == Approx(350.0 / 12.5).epsilon(1e-5));

    options.disparity_offset_px = 8.5;
    REQUIRE_THROWS_WITH(parse_calibration(text, "rig.yaml", options),
                        Catch::Contains("disparity_offset_px"));
    options.disparity_offset_px = std::nan("");
    REQUIRE_THROWS_WITH(parse_calibration(text, "rig.yaml", options),
                        Catch::Contains("disparity_offset_px"));
}
