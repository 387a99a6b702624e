#include <catch2/catch.hpp>

#include <cmath>
#include <stdexcept>

#include "../sample_inputs.hpp"
#include "cloud_analysis/pipeline/rig_fit.hpp"

using namespace cloud_analysis;

namespace {

StereoCamera rig(int width, int height, double fx, double baseline) {
    StereoCamera c;
    c.width_px = width;
    c.height_px = height;
    c.fx_px = c.fy_px = fx;
    c.cx_px = c.cx_right_px = width / 2.0;
    c.cy_px = height / 2.0;
    c.baseline_m = baseline;
    return c;
}

ExtractOptions extract_defaults() {
    ExtractOptions e;
    e.classes = load_class_config(default_class_config_path());
    return e;
}

}  // namespace

TEST_CASE("the disparity range reaches the minimum depth on each rig", "[pipeline][rig]") {
    const AnalyseOptions options;  // --min-depth 3
    const ExtractOptions extract = extract_defaults();
    struct Case {
        StereoCamera camera;
        int num_disparities;
    };
    const Case cases[] = {
        {rig(1242, 375, 721.5377, 0.5327), 128},  // KITTI: 128 disparities, as tuned
        {rig(2048, 1024, 2262.52, 0.2093), 160},  // Cityscapes
        {rig(1280, 720, 640.0, 0.05), 16},        // RealSense-like: 10.7 px at 3 m
        {rig(1232, 1028, 1947.0, 0.30), 192},     // a 5 MP rig analysed at half resolution
        {rig(2464, 2056, 3894.0, 0.30), 368},     // the same at full resolution
    };
    for (const auto& c : cases) {
        const RigFit fit = fit_to_rig(options, extract, c.camera);
        INFO("fx " << c.camera.fx_px << " baseline " << c.camera.baseline_m);
        CHECK(fit.analyse.disparity.num_disparities == c.num_disparities);
        CHECK(fit.range_from_min_depth);
        CHECK(fit.nearest_depth_m <= 3.0 * 1.1);
        CHECK(fit.warnings.empty());
    }
}

TEST_CASE("a given range short of the minimum depth is kept and warned about", "[pipeline][rig]") {
    AnalyseOptions options;
    options.rig.given = {"num_disparities"};
    const RigFit fit = fit_to_rig(options, extract_defaults(), rig(2464, 2056, 3894.0, 0.30));
    CHECK(fit.analyse.disparity.num_disparities == 128);
    CHECK_FALSE(fit.range_from_min_depth);
    CHECK(fit.nearest_depth_m == Approx(3894.0 * 0.30 / 127.0));
    REQUIRE(fit.warnings.size() == 1);
    CHECK_THAT(fit.warnings[0], Catch::Contains("reach 9.2 m") && Catch::Contains("--min-depth"));
    // Without a minimum depth nothing is asked of the range.
    options.rig.min_depth_m = 0.0;
    options.rig.given.clear();
    CHECK(fit_to_rig(options, extract_defaults(), rig(2464, 2056, 3894.0, 0.30)).warnings.empty());
}

TEST_CASE("pixel settings scale with the focal length, counts with its square", "[pipeline][rig]") {
    const AnalyseOptions options;
    const ExtractOptions extract = extract_defaults();
    SECTION("KITTI's focal length changes nothing") {
        const RigFit fit = fit_to_rig(options, extract, rig(1242, 375, 721.5377, 0.54));
        CHECK(fit.scale == Approx(1.0));
        CHECK(fit.analyse.reproject.depth_edge_rows == options.reproject.depth_edge_rows);
        CHECK(fit.extract.shadow_radius_px == extract.shadow_radius_px);
        CHECK(fit.extract.classes.find("car").min_points == extract.classes.find("car").min_points);
        CHECK(fit.extract.point_lattice_px == 1);
    }
    SECTION("three times the focal length") {
        const RigFit fit = fit_to_rig(options, extract, rig(2400, 1000, 3 * 721.5377, 0.2));
        CHECK(fit.scale == Approx(3.0));
        // The matcher works on image texture, in pixels of any camera.
        CHECK(fit.analyse.disparity.block_size == options.disparity.block_size);
        CHECK(fit.analyse.disparity.speckle_window_size == 100);
        CHECK(fit.analyse.reproject.depth_edge_rows == 3 * options.reproject.depth_edge_rows);
        CHECK(fit.analyse.geometry.column_bin_px == 3 * options.geometry.column_bin_px);
        CHECK(fit.analyse.geometry.min_cell_pixels == 9 * options.geometry.min_cell_pixels);
        CHECK(fit.analyse.geometry.edge_step_px == 3 * options.geometry.edge_step_px);
        CHECK(fit.extract.shadow_radius_px == 3 * extract.shadow_radius_px);
        CHECK(fit.extract.strip_beside_width_px == Approx(3 * extract.strip_beside_width_px));
        // Things on every second pixel of every second row: their counts scale by (3 / 2)^2,
        // stuff's (every pixel) by 3^2.
        CHECK(fit.extract.point_lattice_px == 2);
        CHECK(fit.extract.classes.find("car").min_points ==
              std::lround(2.25 * extract.classes.find("car").min_points));
        CHECK(fit.extract.classes.find("building").min_points ==
              9 * extract.classes.find("building").min_points);
        CHECK(fit_to_rig(options, extract, rig(4000, 2000, 5 * 721.5377, 0.2))
                  .extract.point_lattice_px == 4);
    }
    SECTION("a fifth of the focal length keeps lengths and counts at least 1") {
        const RigFit fit = fit_to_rig(options, extract, rig(621, 188, 721.5377 / 5, 0.54));
        CHECK(fit.analyse.geometry.min_cell_pixels == 1);
        CHECK(fit.analyse.geometry.edge_step_px == 1);
        CHECK(fit.extract.image_radius_px == 1);
        CHECK(fit.extract.point_lattice_px == 1);
    }
    SECTION("settings the user gave stay as given") {
        AnalyseOptions given = options;
        given.rig.given = {"depth_edge_rows", "min_points", "point_lattice_px"};
        ExtractOptions every_pixel = extract;
        every_pixel.point_lattice_px = 1;
        const RigFit fit = fit_to_rig(given, every_pixel, rig(2400, 1000, 3 * 721.5377, 0.2));
        CHECK(fit.extract.point_lattice_px == 1);
        CHECK(fit.analyse.reproject.depth_edge_rows == options.reproject.depth_edge_rows);
        CHECK(fit.extract.classes.find("car").min_points == extract.classes.find("car").min_points);
        CHECK(fit.extract.shadow_radius_px == 3 * extract.shadow_radius_px);
    }
    SECTION("off") {
        AnalyseOptions off = options;
        off.rig.scale_pixel_settings = false;
        const RigFit fit = fit_to_rig(off, extract, rig(2400, 1000, 3 * 721.5377, 0.2));
        CHECK(fit.scale == 1.0);
        CHECK(fit.extract.shadow_radius_px == extract.shadow_radius_px);
        CHECK(fit.extract.point_lattice_px == 1);
    }
}

TEST_CASE("an image narrower than the fitted range is refused", "[pipeline][rig]") {
    CHECK_THROWS_WITH(fit_to_rig(AnalyseOptions{}, extract_defaults(), rig(300, 200, 3894, 0.3)),
                      Catch::Contains("image too narrow") && Catch::Contains("--min-depth"));
}

TEST_CASE("a frame over the pixel limit is analysed at half resolution", "[pipeline][rig]") {
    AnalyseOptions options;
    const InputPaths paths = test_samples::synthetic_paths();
    const LoadedInputs whole = load_inputs(paths, options);
    options.rig.half_resolution_above_px = 621 * 188 - 1;
    const LoadedInputs half = load_inputs(paths, options);
    CHECK(half.resolution_scale == 0.5);
    CHECK(half.read_width_px == 621);
    CHECK(half.left.width_px == 310);
    CHECK(half.left.height_px == 94);
    CHECK(half.semantic.width_px == 310);
    const StereoCamera& a = whole.calibration.camera;
    const StereoCamera& b = half.calibration.camera;
    CHECK(b.fx_px == Approx(a.fx_px / 2));
    // The centre of pixel u of the half image is 2u + 0.5 of the whole one.
    CHECK(2 * b.cx_px + 0.5 == Approx(a.cx_px));
    CHECK(b.width_px == 310);
    // Labels are picked, never blended: every colour of the half image is one of the palette's.
    for (std::size_t i = 0; i < half.semantic.data.size(); i += 3) {
        bool found = false;
        for (const auto& c : half.palette.classes) {
            found = found || (half.semantic.data[i] == c.colour[0] &&
                              half.semantic.data[i + 1] == c.colour[1] &&
                              half.semantic.data[i + 2] == c.colour[2]);
        }
        REQUIRE(found);
    }
    // The analysis of the half frame still sees the scene's cars at metric depths.
    const AnalyseResult r = analyse(half, fit_to_rig(options, ExtractOptions{}, b).analyse);
    CHECK(r.cloud.size() > 10000);
    CHECK(analysis_warnings(half, r).front().find("half resolution") != std::string::npos);
}
