// split_oversized with --row-split partition: a row of things end to end parted as one
// optimisation over the cuts (partition_row).

#include <algorithm>
#include <limits>
#include <numeric>
#include <optional>
#include <string>
#include <vector>

#include <catch2/catch.hpp>

#include "cloud_analysis/entities/extract.hpp"
#include "cloud_analysis/entities/row_split.hpp"
#include "stereoscene/support/angles.hpp"

using namespace cloud_analysis;
using stereoscene::support::kPi;

namespace {

/// KITTI's focal length times baseline, px m.
constexpr double kKittiFb = 721.5377 * 0.54;

/// A car's side seen along +z at x = -1.1 from z0 to z1, 0.3 m up to `top` above the ground
/// (GroundPlane{}: y = 1.65 m below the camera), a point every 5 cm.
void add_side(std::vector<Eigen::Vector3f>& pts, float z0, float z1, float top) {
    for (float z = z0; z <= z1; z += 0.05f) {
        for (float h = 0.3f; h <= top; h += 0.05f) pts.emplace_back(-1.1f, 1.65f - h, z);
    }
}

/// The box of the points, along +z.
OrientedBox box_along_z(const std::vector<Eigen::Vector3f>& pts) {
    float lo = std::numeric_limits<float>::max(), hi = -lo;
    for (const auto& p : pts) {
        lo = std::min(lo, p.z());
        hi = std::max(hi, p.z());
    }
    OrientedBox box;
    box.centre_m = Eigen::Vector3d(-1.1, 0.9, 0.5 * (lo + hi));
    box.theta = -kPi / 2.0;
    box.L_m = hi - lo;
    box.W_m = 1.8;
    box.H_m = 1.45;
    return box;
}

instances::Split partition(const std::vector<Eigen::Vector3f>& pts, double fb_px_m = 0.0,
                           const std::optional<Eigen::Vector2d>& truncation_xz = {}) {
    const auto config = load_class_config(std::string(STEREOSCENE_SOURCE_DIR) +
                                          "/assets/classes/entity_config.json");
    ExtractOptions options;
    options.row_split = "partition";
    instances::Indices idx(pts.size());
    std::iota(idx.begin(), idx.end(), std::size_t{0});
    return instances::split_oversized(pts, idx, box_along_z(pts), config.find("car"), GroundPlane{},
                                      options, truncation_xz, fb_px_m);
}

/// The z extents of the split's pieces, nearest first.
std::vector<std::pair<float, float>> extents(const std::vector<Eigen::Vector3f>& pts,
                                             const instances::Split& split) {
    std::vector<std::pair<float, float>> out;
    for (const auto& part : split.parts) {
        float lo = std::numeric_limits<float>::max(), hi = -lo;
        for (std::size_t i : part) {
            lo = std::min(lo, pts[i].z());
            hi = std::max(hi, pts[i].z());
        }
        out.emplace_back(lo, hi);
    }
    std::sort(out.begin(), out.end());
    return out;
}

}  // namespace

TEST_CASE("a partitioned row parts its cars in the gaps between them whatever their lengths",
          "[entities][split][partition]") {
    // A 3.7 m car, a 4.5 m one and a 5.2 m van, 0.6 m apart.
    std::vector<Eigen::Vector3f> pts;
    add_side(pts, 8.0f, 11.7f, 1.4f);
    add_side(pts, 12.3f, 16.8f, 1.45f);
    add_side(pts, 17.4f, 22.6f, 1.9f);
    const auto split = partition(pts);
    REQUIRE(split.parts.size() == 3);
    CHECK(split.at_gaps);
    const auto e = extents(pts, split);
    CHECK(e[0].second < 12.0f);
    CHECK(e[1].first > 12.0f);
    CHECK(e[1].second < 17.1f);
    CHECK(e[2].first > 17.1f);
}

TEST_CASE("a partitioned row of touching cars is cut where the lengths say",
          "[entities][split][partition]") {
    // Two 4.4 m cars bumper to bumper: no gap, no valley; 8.8 m is two cars, not one.
    std::vector<Eigen::Vector3f> pts;
    add_side(pts, 8.0f, 16.8f, 1.45f);
    const auto split = partition(pts);
    REQUIRE(split.parts.size() == 2);
    CHECK_FALSE(split.at_gaps);
    const auto e = extents(pts, split);
    CHECK(e[0].second == Approx(12.4f).margin(0.5f));
}

TEST_CASE("range smear explains a long far blob as one car, not two halves",
          "[entities][split][partition]") {
    // 6.8 m of points at 26-33 m: at KITTI's fb one surface spreads about 1 m along the ray
    // there, so one car seen long; with a perfect matcher (fb unknown: no spread) two.
    std::vector<Eigen::Vector3f> pts;
    add_side(pts, 26.0f, 32.8f, 1.45f);
    CHECK(partition(pts, kKittiFb).parts.size() == 1);
    CHECK(partition(pts).parts.size() == 2);
}

TEST_CASE("a partitioned row cut by the image's edge leaves its near piece short",
          "[entities][split][partition]") {
    // 2.5 m of a car whose near end the image's edge hides, a 0.5 m gap, a 4.4 m car: the near
    // piece is not padded to a car's length with the second car's first metres.
    std::vector<Eigen::Vector3f> pts;
    add_side(pts, 6.0f, 8.5f, 1.45f);
    add_side(pts, 9.0f, 13.4f, 1.45f);
    const auto split = partition(pts, 0.0, Eigen::Vector2d(-1.1, 6.0));
    REQUIRE(split.parts.size() == 2);
    const auto e = extents(pts, split);
    CHECK(e[0].second < 8.8f);
    CHECK(e[1].first > 8.8f);
}

TEST_CASE("the row split is rules or partition", "[entities][split][partition]") {
    ExtractOptions options;
    options.row_split = "dp";
    CHECK_THROWS_WITH(options.validate(), Catch::Contains("row_split"));
}
