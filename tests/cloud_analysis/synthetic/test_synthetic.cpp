#include <catch2/catch.hpp>

#include "cloud_analysis/cloud/reproject.hpp"
#include "cloud_analysis/cloud/semantic.hpp"
#include "cloud_analysis/stereo/disparity.hpp"
#include "cloud_analysis/synthetic/synthetic.hpp"

using namespace cloud_analysis;

namespace {
const SyntheticScene& scene() {
    static const SyntheticScene s = make_synthetic_scene(SyntheticOptions{});
    return s;
}
}  // namespace

TEST_CASE("the synthetic road's disparity is f*B/Z of a plane 1.65 m down", "[synthetic]") {
    const SyntheticScene& s = scene();
    const int v = s.camera.height_px - 1, u = s.camera.width_px / 2;
    const double z = 1.65 * s.camera.fy_px / (v - s.camera.cy_px);
    const float d = s.disparity.disparity_px[static_cast<std::size_t>(v) * s.camera.width_px + u];
    CHECK(d == Approx(s.camera.fx_px * s.camera.baseline_m / z).epsilon(1e-4));
    // The top-right corner looks at the sky: no disparity.
    CHECK(s.disparity.disparity_px[static_cast<std::size_t>(s.camera.width_px) - 1] <= 0.0f);
    CHECK(s.truth.entities.size() == 10);
}

TEST_CASE("the synthetic scene is deterministic for a seed and differs across seeds",
          "[synthetic]") {
    SyntheticOptions small;
    small.width_px = 160;
    small.height_px = 64;
    small.fx_px = 90.0;
    const SyntheticScene a = make_synthetic_scene(small);
    const SyntheticScene b = make_synthetic_scene(small);
    small.seed = 2;
    const SyntheticScene c = make_synthetic_scene(small);
    CHECK(a.left.data == b.left.data);
    CHECK(a.right.data == b.right.data);
    CHECK(a.left.data != c.left.data);
    CHECK(a.semantic.data == c.semantic.data);
}

TEST_CASE("SGBM with the default settings recovers the synthetic ground-truth disparity",
          "[synthetic][disparity]") {
    const SyntheticScene& s = scene();
    const DisparityMap d = compute_disparity(s.left, s.right, DisparityOptions{});
    const DisparityScore score = score_disparity(d, s.disparity);
    CHECK(score.d1_valid < 0.03);
    CHECK(score.epe_px < 0.5);
    CHECK(score.density > 0.7);
}

TEST_CASE("reprojecting the synthetic ground truth puts the road 1.65 m below the camera",
          "[synthetic][reproject]") {
    const SyntheticScene& s = scene();
    const Palette city = load_palette("cityscapes");
    const ClassImage classes = classify_pixels(s.semantic, city);
    CHECK(classes.void_pixels == 0);
    const LabeledCloud cloud =
        reproject(s.disparity, s.camera, s.left, classes, ReprojectOptions{});
    const std::uint16_t road = find_class(city, "road");
    std::size_t n = 0;
    double sum_y = 0.0, max_range = 0.0;
    for (std::size_t i = 0; i < cloud.size(); ++i) {
        max_range = std::max(max_range, static_cast<double>(cloud.xyz_m[i].norm()));
        if (cloud.class_index[i] != road) continue;
        ++n;
        sum_y += static_cast<double>(cloud.xyz_m[i].y());
    }
    REQUIRE(n > 1000);
    CHECK(sum_y / static_cast<double>(n) == Approx(1.65).margin(0.01));
    CHECK(max_range <= 80.0);
}
