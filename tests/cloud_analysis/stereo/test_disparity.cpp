#include <catch2/catch.hpp>

#include <filesystem>
#include <fstream>
#include <random>

#include "cloud_analysis/stereo/disparity.hpp"

using namespace cloud_analysis;

namespace {

/// Random-dot pair of a fronto-parallel plane at disparity `d`: right(u) = left(u + d).
std::pair<ImageU8, ImageU8> random_dot_pair(int w, int h, int d, unsigned seed) {
    std::mt19937 rng(seed);
    std::uniform_int_distribution<int> dot(0, 255);
    ImageU8 left{w, h, 1, std::vector<std::uint8_t>(static_cast<std::size_t>(w) * h)};
    for (auto& p : left.data) p = static_cast<std::uint8_t>(dot(rng));
    ImageU8 right = left;
    for (int v = 0; v < h; ++v) {
        for (int u = 0; u < w; ++u) {
            const std::size_t i = static_cast<std::size_t>(v) * w + u;
            right.data[i] = u + d < w ? left.data[i + d] : static_cast<std::uint8_t>(dot(rng));
        }
    }
    return {left, right};
}

}  // namespace

TEST_CASE("a random-dot pair shifted by 12 px gives disparity 12", "[disparity]") {
    const int d = 12;
    auto [left, right] = random_dot_pair(160, 80, d, 7);
    DisparityOptions options;
    options.num_disparities = 32;
    const DisparityMap map = compute_disparity(left, right, options);
    REQUIRE(map.width_px == 160);
    std::size_t valid = 0, exact = 0;
    for (int v = 10; v < 70; ++v) {
        for (int u = 60; u < 150; ++u) {
            const float got = map.disparity_px[static_cast<std::size_t>(v) * 160 + u];
            if (got <= 0.0f) continue;
            ++valid;
            if (std::abs(got - static_cast<float>(d)) <= 0.25f) ++exact;
        }
    }
    CHECK(valid > 60 * 90 * 9 / 10);
    CHECK(exact > valid * 95 / 100);
}

TEST_CASE("the left-right check and WLS keep the known disparity", "[disparity]") {
    auto [left, right] = random_dot_pair(160, 80, 20, 11);
    DisparityOptions options;
    options.num_disparities = 32;
    options.lr_check = true;
    const DisparityMap checked = compute_disparity(left, right, options);
    options.lr_check = false;
    options.wls = true;
    const DisparityMap filtered = compute_disparity(left, right, options);
    const std::size_t centre = 40 * 160 + 100;
    CHECK(checked.disparity_px[centre] == Approx(20.0f).margin(0.25));
    CHECK(filtered.disparity_px[centre] == Approx(20.0f).margin(0.5));
}

TEST_CASE("disparity options name the bad field", "[disparity]") {
    DisparityOptions o;
    o.num_disparities = 100;
    REQUIRE_THROWS_WITH(o.validate(), Catch::StartsWith("num_disparities"));
    o = {};
    o.block_size = 4;
    REQUIRE_THROWS_WITH(o.validate(), Catch::StartsWith("block_size"));
    o = {};
    o.mode = "fast";
    REQUIRE_THROWS_WITH(o.validate(), Catch::StartsWith("mode"));
    CHECK_NOTHROW(opencv_sample_disparity_options().validate());
}

TEST_CASE("KITTI D1-all counts errors over 3 px and 5 % and missing estimates", "[disparity]") {
    DisparityMap gt{4, 1, {10.0f, 100.0f, 50.0f, kNoDisparity}};
    // err 4 px > 3 and > 5 % of 10: outlier; err 4 px on 100 is < 5 %: inlier; missing: outlier.
    DisparityMap est{4, 1, {14.0f, 104.0f, kNoDisparity, 30.0f}};
    const DisparityScore s = score_disparity(est, gt);
    CHECK(s.gt_pixels == 3);
    CHECK(s.est_pixels == 2);
    CHECK(s.d1_all == Approx(2.0 / 3.0));
    CHECK(s.d1_valid == Approx(0.5));
    CHECK(s.epe_px == Approx(4.0));
    CHECK(s.density == Approx(2.0 / 3.0));
    // Errors over 3 px are left out of the bias: every band is empty here.
    CHECK(s.bias_px[0] == 0.0);
    CHECK(s.bias_px[2] == 0.0);
}

TEST_CASE("the disparity bias is the median signed error by band of true disparity",
          "[disparity]") {
    DisparityMap gt{6, 1, {10.0f, 20.0f, 22.0f, 30.0f, 60.0f, 80.0f}};
    DisparityMap est{6, 1, {9.5f, 19.5f, 21.0f, 30.25f, 61.0f, 90.0f}};
    const DisparityScore s = score_disparity(est, gt);
    CHECK(s.bias_px[0] == Approx(-0.5));  // -0.5, -0.5, -1.0
    CHECK(s.bias_px[1] == Approx(0.25));  // +0.25
    CHECK(s.bias_px[2] == Approx(1.0));   // +1.0; the 10 px error is left out
}

TEST_CASE("KITTI disparity PNGs round-trip at 1/256 px", "[disparity][io]") {
    DisparityMap map{3, 2, {0.5f, 12.25f, kNoDisparity, 100.0f, 255.99f, 3.0f}};
    const auto path = std::filesystem::temp_directory_path() / "stereoscene_test_disp_kitti.png";
    {
        std::ofstream out(path, std::ios::binary);
        out << encode_kitti_disparity_png(map);
    }
    const DisparityMap back = read_kitti_disparity(path);
    std::filesystem::remove(path);
    REQUIRE(back.width_px == 3);
    REQUIRE(back.height_px == 2);
    for (std::size_t i = 0; i < map.disparity_px.size(); ++i) {
        if (map.disparity_px[i] > 0.0f) {
            CHECK(back.disparity_px[i] == Approx(map.disparity_px[i]).margin(1.0 / 512));
        } else {
            CHECK(back.disparity_px[i] <= 0.0f);
        }
    }
}

TEST_CASE("left padding gives the border band its disparity and without it the band is empty",
          "[disparity]") {
    auto [left, right] = random_dot_pair(160, 60, 12, 5);
    DisparityOptions options;
    options.num_disparities = 32;
    const auto band_hits = [&](const DisparityMap& map) {
        int exact = 0;
        for (int v = 10; v < 50; ++v) {
            for (int u = 16; u < 28; ++u) {  // inside the 32 px band, right of u = d
                const float d = map.disparity_px[static_cast<std::size_t>(v) * 160 + u];
                if (std::abs(d - 12.0f) <= 0.25f) ++exact;
            }
        }
        return exact;
    };
    CHECK(band_hits(compute_disparity(left, right, options)) > 40 * 12 * 9 / 10);
    options.pad_left = false;
    CHECK(band_hits(compute_disparity(left, right, options)) == 0);
}

TEST_CASE("a matcher reused across frames gives the same maps as one-off matchers",
          "[disparity][batch]") {
    auto [left_a, right_a] = random_dot_pair(160, 80, 12, 3);
    auto [left_b, right_b] = random_dot_pair(200, 60, 20, 4);  // another size in between
    DisparityOptions options;
    options.num_disparities = 32;
    DisparityMatcher matcher(options);
    const DisparityMap a1 = matcher.compute(left_a, right_a);
    const DisparityMap b = matcher.compute(left_b, right_b);
    const DisparityMap a2 = matcher.compute(left_a, right_a);
    CHECK(a1.disparity_px == compute_disparity(left_a, right_a, options).disparity_px);
    CHECK(b.disparity_px == compute_disparity(left_b, right_b, options).disparity_px);
    CHECK(a2.disparity_px == a1.disparity_px);
    CHECK(b.width_px == 200);
}

TEST_CASE("half-resolution matching recovers the full-scale disparity", "[disparity][preset]") {
    const int d = 20;
    auto [left, right] = random_dot_pair(240, 120, d, 5);
    DisparityOptions options;
    options.num_disparities = 64;  // 32 at half scale
    options.downscale = 2;
    options.block_size = 5;
    const DisparityMap map = compute_disparity(left, right, options);
    REQUIRE(map.width_px == 240);
    REQUIRE(map.height_px == 120);
    std::size_t valid = 0, close = 0;
    for (int v = 10; v < 110; ++v) {
        for (int u = 80; u < 230; ++u) {
            const float got = map.disparity_px[static_cast<std::size_t>(v) * 240 + u];
            if (got <= 0.0f) continue;
            ++valid;
            if (std::abs(got - static_cast<float>(d)) <= 1.0f) ++close;
        }
    }
    CHECK(valid > 100 * 150 * 8 / 10);
    CHECK(close > valid * 9 / 10);
}

TEST_CASE("the speed presets differ as documented and an unknown one is refused",
          "[disparity][preset]") {
    CHECK(disparity_preset("tuned").downscale == 1);
    CHECK(disparity_preset("fast").downscale == 2);
    CHECK(disparity_preset("quality").mode == disparity_preset("tuned").mode);
    CHECK(disparity_preset("quality").wls);
    CHECK(disparity_preset("opencv-sample").block_size == 3);
    CHECK_THROWS_WITH(disparity_preset("turbo"), Catch::Contains("preset"));
    DisparityOptions o;
    o.downscale = 3;
    CHECK_THROWS_WITH(o.validate(), Catch::Contains("downscale"));
}

TEST_CASE("an RGB pair of grey pixels matches exactly like the grey pair, at both scales",
          "[disparity]") {
    auto [left, right] = random_dot_pair(160, 80, 12, 9);
    const auto to_rgb = [](const ImageU8& g) {
        ImageU8 c{g.width_px, g.height_px, 3, std::vector<std::uint8_t>(g.data.size() * 3)};
        for (std::size_t i = 0; i < g.data.size(); ++i) {
            c.data[3 * i] = c.data[3 * i + 1] = c.data[3 * i + 2] = g.data[i];
        }
        return c;
    };
    const ImageU8 left_rgb = to_rgb(left), right_rgb = to_rgb(right);
    for (const int downscale : {1, 2}) {
        DisparityOptions options;
        options.num_disparities = 32;
        options.downscale = downscale;
        DisparityMatcher matcher(options);
        const DisparityMap grey = matcher.compute(left, right);
        const DisparityMap colour = matcher.compute(left_rgb, right_rgb);
        CHECK(colour.disparity_px == grey.disparity_px);
        CHECK(grey.valid_count() > 160 * 80 / 2);
    }
}
