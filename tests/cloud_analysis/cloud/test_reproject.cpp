#include <catch2/catch.hpp>

#include <random>

#include <Eigen/Core>

#include "cloud_analysis/cloud/reproject.hpp"
#include "cloud_analysis/entities/extract.hpp"
#include "cloud_analysis/stereo/calibration.hpp"

using namespace cloud_analysis;

namespace {

StereoCamera kitti_like_camera(int w, int h) {
    StereoCamera cam;
    cam.width_px = w;
    cam.height_px = h;
    cam.fx_px = 721.5;
    cam.fy_px = 719.0;  // not square: exercises Q(1,1) = fx / fy
    cam.cx_px = 30.0;
    cam.cx_right_px = 26.5;  // cx - cx_right = 3.5 px: disparities below that are beyond infinity
    cam.cy_px = 12.0;
    cam.baseline_m = 0.54;
    return cam;
}

/// The definition: (X, Y, Z, W) = Q (u, v, d, 1), one 4x4 product per pixel, pushed back in
/// pixel order.
LabeledCloud naive_reproject(const DisparityMap& map, const StereoCamera& cam, const ImageU8& img,
                             const ClassImage& classes, const ReprojectOptions& o) {
    const Eigen::Matrix4d Q = reprojection_matrix(cam);
    LabeledCloud cloud;
    for (int v = 0; v < map.height_px; ++v) {
        for (int u = 0; u < map.width_px; ++u) {
            const std::size_t i = static_cast<std::size_t>(v) * map.width_px + u;
            const double d = map.disparity_px[i];
            if (!(d > o.min_disparity_px)) continue;
            const std::uint16_t cls =
                classes.class_index.empty() ? kVoidClass : classes.class_index[i];
            if (cls == kVoidClass && !o.keep_void) continue;
            const Eigen::Vector4d p = Q * Eigen::Vector4d(u, v, d, 1.0);
            if (!(p[3] > 0.0)) continue;
            const Eigen::Vector3d xyz = p.head<3>() / p[3];
            if (!(xyz.squaredNorm() <= o.max_range_m * o.max_range_m)) continue;
            cloud.xyz_m.push_back(xyz.cast<float>());
            const std::uint8_t* c = img.at(u, v);
            cloud.colour.push_back(img.channels == 3 ? Rgb{c[0], c[1], c[2]}
                                                     : Rgb{c[0], c[0], c[0]});
            cloud.class_index.push_back(cls);
            cloud.pixel.push_back(static_cast<std::uint32_t>(i));
        }
    }
    return cloud;
}

/// w x h disparities drawn uniformly from [lo, hi).
DisparityMap random_disparities(int w, int h, float lo, float hi, std::mt19937& rng) {
    std::uniform_real_distribution<float> disparity(lo, hi);
    DisparityMap map{w, h, std::vector<float>(static_cast<std::size_t>(w) * h)};
    for (auto& d : map.disparity_px) d = disparity(rng);
    return map;
}

/// w x h classes drawn uniformly from 0 .. void_index, void_index standing for void.
ClassImage random_classes(int w, int h, int void_index, std::mt19937& rng) {
    std::uniform_int_distribution<int> klass(0, void_index);
    ClassImage classes{w, h, std::vector<std::uint16_t>(static_cast<std::size_t>(w) * h), 0};
    for (auto& c : classes.class_index) {
        const int k = klass(rng);
        c = k == void_index ? kVoidClass : static_cast<std::uint16_t>(k);
    }
    return classes;
}

}  // namespace

TEST_CASE("the reprojection agrees with the 4x4 Q product on random maps", "[reproject]") {
    const int w = 64, h = 24;
    const std::size_t n = static_cast<std::size_t>(w) * h;
    std::mt19937 rng(11);
    const DisparityMap map =
        random_disparities(w, h, -2.0f, 40.0f, rng);  // some missing, some < 3.5
    std::uniform_int_distribution<int> byte(0, 255);
    ImageU8 rgb{w, h, 3, std::vector<std::uint8_t>(n * 3)};
    for (auto& b : rgb.data) b = static_cast<std::uint8_t>(byte(rng));
    ImageU8 grey{w, h, 1, std::vector<std::uint8_t>(n)};
    for (auto& b : grey.data) b = static_cast<std::uint8_t>(byte(rng));
    const ClassImage classes = random_classes(w, h, 4, rng);
    const StereoCamera cam = kitti_like_camera(w, h);

    ReprojectOptions options;
    options.max_range_m = 60.0;  // drops the disparities just above 3.5 px
    options.min_disparity_px = 0.5;
    for (const bool keep_void : {true, false}) {
        for (const ImageU8* img : {&rgb, &grey}) {
            for (const ClassImage& cls : {classes, ClassImage{}}) {
                options.keep_void = keep_void;
                const LabeledCloud got = reproject(map, cam, *img, cls, options);
                const LabeledCloud want = naive_reproject(map, cam, *img, cls, options);
                REQUIRE(got.size() == want.size());
                REQUIRE(got.width_px == w);
                REQUIRE(got.height_px == h);
                CHECK(got.pixel == want.pixel);
                CHECK(got.class_index == want.class_index);
                CHECK(got.colour == want.colour);
                for (std::size_t i = 0; i < got.size(); ++i) {
                    for (int k = 0; k < 3; ++k) {
                        CHECK(got.xyz_m[i][k] == Approx(want.xyz_m[i][k]).epsilon(1e-6));
                    }
                }
            }
        }
    }
    // The filters did something: void points, far points and points beyond infinity.
    options.keep_void = false;
    const std::size_t labelled = reproject(map, cam, grey, classes, options).size();
    options.keep_void = true;
    const std::size_t all = reproject(map, cam, grey, classes, options).size();
    CHECK(labelled < all);
    CHECK(all < map.valid_count());
}

TEST_CASE("disparities at or below cx - cx_right are beyond infinity and give no point",
          "[reproject]") {
    const StereoCamera cam = kitti_like_camera(4, 1);
    DisparityMap map{4, 1, {3.0f, 3.5f, 4.0f, 13.5f}};
    const ImageU8 grey{4, 1, 1, {10, 20, 30, 40}};
    ReprojectOptions options;
    options.max_range_m = 1000.0;
    const LabeledCloud cloud = reproject(map, cam, grey, ClassImage{}, options);
    REQUIRE(cloud.size() == 2);
    CHECK(cloud.pixel == std::vector<std::uint32_t>{2, 3});
    // Z = fx B / (d - (cx - cx_right)): 10 px of effective disparity at u = 3 -> 38.961 m.
    CHECK(cloud.xyz_m[1].z() == Approx(721.5 * 0.54 / 10.0).epsilon(1e-6));
    CHECK(cloud.colour[1] == Rgb{40, 40, 40});
}

TEST_CASE("a disparity map has a valid pixel when any pixel holds a value", "[reproject]") {
    DisparityMap map;
    map.width_px = 4;
    map.height_px = 3;
    map.disparity_px.assign(12, 0.0f);
    CHECK_FALSE(map.any_valid());
    CHECK(map.valid_count() == 0);
    map.disparity_px[11] = 0.5f;
    CHECK(map.any_valid());
    CHECK(map.valid_count() == 1);
}

TEST_CASE("reprojecting by class gives the split of the reprojected cloud, without the cloud",
          "[reproject]") {
    const int w = 96, h = 40;
    const std::size_t n = static_cast<std::size_t>(w) * h;
    std::mt19937 rng(5);
    const DisparityMap map = random_disparities(w, h, -2.0f, 60.0f, rng);
    const ImageU8 grey{w, h, 1, std::vector<std::uint8_t>(n, 128)};
    const ClassImage classes = random_classes(w, h, 5, rng);  // 4 = past the selection
    const StereoCamera cam = kitti_like_camera(w, h);
    // Class 0 every column with pixels (a thing), 1 every 4th column, 2 every 2nd, 3 every 8th.
    ClassSelection selection;
    selection.column_mask = {0, 3, 1, 7};
    selection.keep_pixels = {1, 0, 0, 1};
    selection.max_depth_m = 30.0;  // below the reprojection's range: both limits apply
    ReprojectOptions options;
    options.max_range_m = 50.0;
    std::size_t stuff_points[2] = {0, 0};  // class 1 with every pixel, by keep_void
    std::size_t thing_points[2] = {0, 0};  // class 0
    for (const std::uint32_t lattice : {0u, 1u, 3u}) {
        // The classes with pixels (0, 3) on every (lattice + 1)-th pixel of every such row.
        selection.lattice_mask = lattice;
        for (const bool keep_void : {true, false}) {
            options.keep_void = keep_void;
            const LabeledCloud cloud = reproject(map, cam, grey, classes, options);
            const ClassPoints want = points_by_class(cloud, selection, 2);
            const ClassPoints got = reproject_by_class(map, cam, classes, options, selection);
            CHECK(got.cloud_points == cloud.size());
            CHECK(got.width_px == w);
            CHECK(got.height_px == h);
            CHECK(got.weight == std::vector<std::size_t>{1, 4, 2, 8});
            CHECK(got.pixel == want.pixel);
            REQUIRE(got.xyz_m.size() == 4);
            for (std::size_t k = 0; k < 4; ++k) {
                CHECK(got.xyz_m[k] == want.xyz_m[k]);  // the same floats, in pixel order
                CHECK_FALSE(got.xyz_m[k].empty());
                for (const auto& p : got.xyz_m[k]) CHECK(p.z() < 30.0f);
            }
            CHECK(got.pixel[1].empty());
            // Thinned columns and pixels of the kept points.
            for (const std::uint32_t p : got.pixel[3]) CHECK(p % w % 8 == 0);
            for (const std::uint32_t p : got.pixel[0]) {
                CHECK(((p % w) & lattice) == 0);
                CHECK(((p / w) & lattice) == 0);
            }
            // Stuff is not on the lattice; things lose about all but 1 / (lattice + 1)^2.
            if (lattice == 0) {
                stuff_points[keep_void] = got.xyz_m[1].size();
                thing_points[keep_void] = got.xyz_m[0].size();
            }
            CHECK(got.xyz_m[1].size() == stuff_points[keep_void]);
            const double share = 1.0 / ((lattice + 1.0) * (lattice + 1.0));
            CHECK(static_cast<double>(got.xyz_m[0].size()) ==
                  Approx(share * static_cast<double>(thing_points[keep_void])).epsilon(0.35));
        }
    }
    ClassSelection bad = selection;
    bad.keep_pixels.pop_back();
    CHECK_THROWS_WITH(reproject_by_class(map, cam, classes, options, bad),
                      Catch::Contains("keep_pixels"));
}

TEST_CASE("the depth edge band holds the far pixels within a few rows of a nearer surface",
          "[reproject]") {
    // 40 x 30 px, fb = 400 px m: a far wall at 20 m (d = 20) over rows 0-14, a near car at 10 m
    // (d = 40) over rows 15-29 of columns 10-29. Columns 0-9 hold a side seen along the ray (d
    // from 30 down to 21 across them, the same on every row), column 35 a step of 0.5 m
    // (20 m over 20.5 m); column 25 has no disparity on row 14.
    const MatchBorder border{400.0, 0.0};
    DisparityMap map;
    map.width_px = 40;
    map.height_px = 30;
    map.disparity_px.assign(40 * 30, 20.0f);
    const auto at = [&](int u, int v) -> float& {
        return map.disparity_px[static_cast<std::size_t>(v) * 40 + static_cast<std::size_t>(u)];
    };
    for (int v = 0; v < 30; ++v) {
        for (int u = 0; u < 10; ++u) at(u, v) = 30.0f - static_cast<float>(u);
        if (v >= 15) {
            for (int u = 10; u < 30; ++u) at(u, v) = 40.0f;
            at(35, v) = 400.0f / 20.0f;
        } else {
            at(35, v) = 400.0f / 20.5f;
        }
    }
    at(25, 14) = kNoDisparity;
    const std::vector<std::uint8_t> band = depth_edge_band(map, border, 0.8, 4);
    REQUIRE(band.size() == map.disparity_px.size());
    const auto flagged = [&](int u, int v) {
        return band[static_cast<std::size_t>(v) * 40 + static_cast<std::size_t>(u)] != 0;
    };
    for (int v = 0; v < 30; ++v) {
        CAPTURE(v);
        CHECK(flagged(20, v) == (v >= 11 && v <= 14));  // the wall's 4 rows above the car
        CHECK_FALSE(flagged(5, v));                     // a side: depth changes across columns
        CHECK_FALSE(flagged(35, v));                    // 0.5 m: under the step
    }
    CHECK_FALSE(flagged(25, 14));  // no disparity, no flag
    CHECK(flagged(25, 13));
    // Half the rows: only the wall's 2 rows above the car.
    const std::vector<std::uint8_t> narrow = depth_edge_band(map, border, 0.8, 2);
    CHECK(narrow[10 * 40 + 20] == 0);
    CHECK(narrow[13 * 40 + 20] == 1);
    // No step, no rows or no rig: no band.
    CHECK(depth_edge_band(map, border, 0.0, 4).empty());
    CHECK(depth_edge_band(map, border, 0.8, 0).empty());
    CHECK(depth_edge_band(map, MatchBorder{}, 0.8, 4).empty());
    ReprojectOptions o;
    o.depth_edge_step_m = -1.0;
    CHECK_THROWS_WITH(o.validate(), Catch::Contains("depth_edge_step_m"));
    o.depth_edge_step_m = 0.8;
    o.depth_edge_rows = -1;
    CHECK_THROWS_WITH(o.validate(), Catch::Contains("depth_edge_rows"));
}

TEST_CASE("the reprojections carry the depth edge band of their disparity", "[reproject]") {
    const StereoCamera cam = kitti_like_camera(8, 12);
    DisparityMap map;
    map.width_px = 8;
    map.height_px = 12;
    map.disparity_px.assign(8 * 12, 20.0f);
    for (std::size_t i = 6 * 8; i < map.disparity_px.size(); ++i) map.disparity_px[i] = 60.0f;
    ImageU8 grey;
    grey.width_px = 8;
    grey.height_px = 12;
    grey.channels = 1;
    grey.data.assign(8 * 12, 128);
    ReprojectOptions o;
    CHECK(o.depth_edge_step_m == 0.8);  // on by default
    const LabeledCloud cloud = reproject(map, cam, grey, ClassImage{}, o);
    const std::vector<std::uint8_t> band = depth_edge_band(map, match_border(cam), 0.8, 4);
    CHECK(cloud.depth_edge == band);
    ClassSelection selection;
    selection.column_mask = {0};
    selection.keep_pixels = {1};
    CHECK(reproject_by_class(map, cam, ClassImage{}, o, selection).depth_edge == band);
    CHECK(band[5 * 8] == 1);
    CHECK(band[1 * 8] == 0);
    o.depth_edge_step_m = 0.0;
    CHECK(reproject(map, cam, grey, ClassImage{}, o).depth_edge.empty());
}
