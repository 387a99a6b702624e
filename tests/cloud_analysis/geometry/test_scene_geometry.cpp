#include <algorithm>
#include <cmath>
#include <cstdint>
#include <functional>
#include <string>
#include <utility>
#include <vector>

#include <catch2/catch.hpp>
#include <nlohmann/json.hpp>

#include "../kitti_rig.hpp"
#include "cloud_analysis/cloud/semantic.hpp"
#include "cloud_analysis/geometry/scene_geometry.hpp"
#include "synthetic_scene.hpp"

using cloud_analysis::DisparityMap;
using cloud_analysis::ImageU8;
using cloud_analysis::kNoDisparity;
using cloud_analysis::StereoCamera;
using namespace cloud_analysis::geometry;

namespace {

using test_rigs::kitti_rig;
using test_scenes::Box;
using test_scenes::class_at;
using test_scenes::pixel_of;
using test_scenes::render;
using test_scenes::with_car_from_behind;

/// Pixel `px` of `d` is a car with the default options, and no car once `without` has turned
/// a rule off: the rule is what makes it one.
void check_car_only_with_rule(const DisparityMap& d, const StereoCamera& cam,
                              const cloud_analysis::Palette& palette, std::pair<int, int> px,
                              const std::function<void(GeometryOptions&)>& without) {
    GeometryOptions o;
    CHECK(class_at(derive_semantics(d, cam, ImageU8{}, palette, o), palette, px.first, px.second) ==
          "car");
    without(o);
    CHECK(class_at(derive_semantics(d, cam, ImageU8{}, palette, o), palette, px.first, px.second) !=
          "car");
}

/// A grey image of the rig's size, 120 everywhere but in the image box of the face from
/// (x0, up0) to (x1, up1) at depth z, where `grey(u, v)` paints it.
ImageU8 textured(const StereoCamera& c, double x0, double up0, double x1, double up1, double z,
                 const std::function<int(int, int)>& grey, ImageU8 left = {}) {
    if (left.empty()) {
        left.width_px = c.width_px;
        left.height_px = c.height_px;
        left.channels = 1;
        left.data.assign(static_cast<std::size_t>(c.width_px) * c.height_px, 120);
    }
    const auto [u0, v0] = pixel_of(c, x0, up1, z);
    const auto [u1, v1] = pixel_of(c, x1, up0, z);
    for (int v = v0; v <= v1; ++v) {
        for (int u = u0; u <= u1; ++u) {
            left.data[static_cast<std::size_t>(v) * c.width_px + u] =
                static_cast<std::uint8_t>(std::clamp(grey(u, v), 0, 255));
        }
    }
    return left;
}

/// Stripes 4 px wide: horizontal (a car's bumper, sills, window line), or upright (posts).
int horizontal_stripes(int, int v) { return (v / 4) % 2 ? 60 : 180; }
int upright_stripes(int u, int) { return (u / 4) % 2 ? 20 : 230; }
/// An isotropic texture (grass, leaves): a fixed pseudo-random grey per pixel.
int speckle(int u, int v) {
    return static_cast<int>((u * 7919u + v * 104729u) * 2654435761u >> 24);
}

}  // namespace

TEST_CASE("a road 1.65 m below gives the camera height, no pitch, and road pixels", "[geometry]") {
    const StereoCamera cam = kitti_rig();
    const auto palette = cloud_analysis::load_palette("cityscapes");
    const SceneGeometry g = derive_semantics(render(cam, 1.65, {}), cam, ImageU8{}, palette, {});
    REQUIRE(g.ground.found);
    CHECK(g.ground.camera_height_m == Approx(1.65).margin(0.02));
    CHECK(g.ground.pitch_deg == Approx(0.0).margin(0.2));
    CHECK(g.ground.horizon_v_px == Approx(187.5).margin(2.0));
    CHECK(g.warnings.empty());
    CHECK(class_at(g, palette, 600, 300) == "road");
    CHECK(class_at(g, palette, 600, 50) == "sky");
}

TEST_CASE("a car-shaped object on the road is car, a facade building, a pole pole, a board wall",
          "[geometry]") {
    const StereoCamera cam = kitti_rig();
    const auto palette = cloud_analysis::load_palette("cityscapes");
    // A car seen from behind: its back up to the boot lid, the cabin 0.6 m farther up to the
    // roof (a flat board with one top is a wall or fence: last line).
    const std::vector<Box> boxes = with_car_from_behind({{3.5, 12.0, 15.0, 8.0},     // a facade
                                                         {-4.0, -3.8, 8.0, 4.0},     // a pole
                                                         {-12.0, -6.0, 14.0, 1.2}},  // a wall
                                                        10.0);
    const SceneGeometry g = derive_semantics(render(cam, 1.65, boxes), cam, ImageU8{}, palette, {});
    REQUIRE(g.ground.found);
    const auto [cu, cv] = pixel_of(cam, 0.0, 0.8, 10.0);
    CHECK(class_at(g, palette, cu, cv) == "car");
    const auto [bu, bv] = pixel_of(cam, 6.0, 2.0, 15.0);
    CHECK(class_at(g, palette, bu, bv) == "building");
    const auto [pu, pv] = pixel_of(cam, -3.9, 2.0, 8.0);
    CHECK(class_at(g, palette, pu, pv) == "pole");
    const auto [ru, rv] = pixel_of(cam, 0.0, 0.0, 8.0);
    CHECK(class_at(g, palette, ru, rv) == "road");
    const auto [wu, wv] = pixel_of(cam, -9.0, 0.8, 14.0);
    CHECK(class_at(g, palette, wu, wv) == "wall");
}

TEST_CASE("each segment lists what the rules measured, and its pixels point back to it",
          "[geometry]") {
    const StereoCamera cam = kitti_rig();
    const auto palette = cloud_analysis::load_palette("cityscapes");
    const std::vector<Box> boxes = with_car_from_behind({{3.5, 12.0, 15.0, 8.0}}, 10.0);
    const SceneGeometry g = derive_semantics(render(cam, 1.65, boxes), cam, ImageU8{}, palette, {});
    REQUIRE(g.ground.found);
    REQUIRE(g.segment_of_pixel.size() ==
            static_cast<std::size_t>(cam.width_px) * static_cast<std::size_t>(cam.height_px));
    const auto segment_at = [&](int u, int v) {
        return g.segment_of_pixel[static_cast<std::size_t>(v) * cam.width_px + u];
    };
    const auto [cu, cv] = pixel_of(cam, 0.0, 0.8, 10.0);
    const int car = segment_at(cu, cv);
    REQUIRE(car >= 0);
    const Segment& s = g.segments[static_cast<std::size_t>(car)];
    CHECK(s.label == "car");
    CHECK(s.depth_m == Approx(10.3).margin(0.5));
    CHECK(s.near_m <= s.depth_m);
    CHECK(s.far_m >= s.depth_m);
    CHECK(s.top_m == Approx(1.5).margin(0.1));
    CHECK(s.top_q25_m < s.top_m);
    CHECK(s.low_m < 0.6);
    CHECK(s.width_m == Approx(1.8).margin(0.3));
    CHECK_FALSE(s.tall);
    CHECK(s.cells > 0);
    // The image box holds every pixel of the segment and is tight.
    int u0 = cam.width_px, v0 = cam.height_px, u1 = -1, v1 = -1;
    for (int v = 0; v < cam.height_px; ++v) {
        for (int u = 0; u < cam.width_px; ++u) {
            if (segment_at(u, v) != car) continue;
            u0 = std::min(u0, u);
            v0 = std::min(v0, v);
            u1 = std::max(u1, u);
            v1 = std::max(v1, v);
        }
    }
    CHECK(std::vector<int>{s.u0, s.v0, s.u1, s.v1} == std::vector<int>{u0, v0, u1, v1});
    // Largest first; the facade is tall and a building.
    for (std::size_t k = 1; k < g.segments.size(); ++k) {
        CHECK(g.segments[k - 1].pixels >= g.segments[k].pixels);
    }
    const auto [bu, bv] = pixel_of(cam, 6.0, 2.0, 15.0);
    const int facade = segment_at(bu, bv);
    REQUIRE(facade >= 0);
    CHECK(g.segments[static_cast<std::size_t>(facade)].label == "building");
    CHECK(g.segments[static_cast<std::size_t>(facade)].tall);
    // Written out: the table in the same order, the ids one above the indices.
    const auto doc = nlohmann::json::parse(segments_json(g, "000042"));
    CHECK(doc["frame"] == "000042");
    CHECK(doc["ground"]["found"] == true);
    REQUIRE(doc["segments"].size() == g.segments.size());
    CHECK(doc["segments"][static_cast<std::size_t>(car)]["class"] == "car");
    CHECK(doc["segments"][static_cast<std::size_t>(car)]["box_px"][2] == s.u1);
    const cloud_analysis::ImageU16 ids = segment_ids(g, cam.width_px, cam.height_px);
    CHECK(ids.values[static_cast<std::size_t>(cv) * cam.width_px + cu] == car + 1);
    const auto [ru, rv] = pixel_of(cam, 0.0, 0.0, 8.0);
    REQUIRE(class_at(g, palette, ru, rv) == "road");
    CHECK(ids.values[static_cast<std::size_t>(rv) * cam.width_px + ru] == 0);  // road
}

TEST_CASE("a car 1 m before a bus at 28 m is a car: the bus above its roof is not its top",
          "[geometry]") {
    const StereoCamera cam = kitti_rig();
    const auto palette = cloud_analysis::load_palette("cityscapes");
    // The car's cabin at 28.6 m, the bus's back (3.2 m tall, from 0.3 m up) at 29.6 m: 0.46 px
    // of disparity apart, in the same 1 px bins. Matching noise of +-0.3 px spreads both.
    const std::vector<Box> boxes = with_car_from_behind({{-1.6, 1.4, 29.6, 3.2, 0.3}}, 28.0);
    DisparityMap d = render(cam, 1.65, boxes);
    std::size_t k = 0;
    for (float& x : d.disparity_px) {
        if (x > 0.0f) x += static_cast<float>(0.3 * std::sin(12.9898 * static_cast<double>(k++)));
    }
    // Tops from every pixel of a cell: the bus's side above the roof lifts it out of a car's.
    // (The noise also splits the bus's back over two bins, which the split-surface rule reads
    // as the bus's too: it is off here, to show the top rule alone.)
    check_car_only_with_rule(d, cam, palette, pixel_of(cam, 0.0, 0.6, 28.0),
                             [](GeometryOptions& o) {
                                 o.split_surface_px = 0.0;
                                 o.top_behind_px = 1e5;
                             });
    GeometryOptions o;
    o.split_surface_px = 0.0;
    const auto [u, v] = pixel_of(cam, 0.0, 0.6, 28.0);
    CHECK(class_at(derive_semantics(d, cam, ImageU8{}, palette, o), palette, u, v) == "car");
    o.top_behind_px = 0.0;
    CHECK_THROWS_WITH(o.validate(), Catch::Contains("top_behind_px"));
}

TEST_CASE("a bus's back split over two disparity bins beside a car is the bus's, not the car's",
          "[geometry]") {
    const StereoCamera cam = kitti_rig();
    const auto palette = cloud_analysis::load_palette("cityscapes");
    // A car's back at 29.5 m (13.2 px, 1.5 m high) 0.5 m before a bus's back (3.2 m tall from
    // 0.3 m up, 13.0 px), which the matcher puts at 12.97 px on most rows and at 13.03 px, in
    // the car's 1 px bin, on every fourth row below the layers' border. Those rows do not
    // reach the border often enough to continue across it: beside the car they make cells of
    // their own that link to the car's, above its roof they lift its cells' tops to 2.28 m.
    const std::vector<Box> boxes = {{-1.0, 0.8, 29.5, 1.5}, {-1.6, 2.4, 30.0, 3.2, 0.3}};
    DisparityMap d = render(cam, 1.65, boxes);
    const double fb = cam.fx_px * cam.baseline_m, bus = fb / 30.0;
    for (int v = 0; v < d.height_px; ++v) {
        const double up_m = 1.65 - (v - cam.cy_px) / cam.fy_px * 30.0;
        for (int u = 0; u < d.width_px; ++u) {
            float& x = d.disparity_px[static_cast<std::size_t>(v) * d.width_px + u];
            if (std::abs(double{x} - bus) > 1e-3) continue;
            x = static_cast<float>(v % 4 == 0 && up_m < 2.3 ? 13.03 : 12.97);
        }
    }
    check_car_only_with_rule(d, cam, palette, pixel_of(cam, 0.0, 0.8, 29.5),
                             [](GeometryOptions& o) { o.split_surface_px = 0.0; });
    // The bus's lower rows beside the car are the bus's.
    const auto [u, v] = pixel_of(cam, 1.6, 0.8, 30.0);
    CHECK(class_at(derive_semantics(d, cam, ImageU8{}, palette, {}), palette, u, v) == "building");
    GeometryOptions o;
    o.split_surface_px = -1.0;
    CHECK_THROWS_WITH(o.validate(), Catch::Contains("split_surface_px"));
}

TEST_CASE("a bus's back over a car's roof in the car's disparity bin does not make the car tall",
          "[geometry]") {
    const StereoCamera cam = kitti_rig();
    const auto palette = cloud_analysis::load_palette("cityscapes");
    // A car's back at 28.2 m (13.82 px, 1.6 m high) and, 1.7 m beyond, a bus's back (3.2 m
    // tall from 0.3 m up) that the matcher locks at 13.03 px: both in the car's 1 px bin. Over
    // the roof the bus's rows run on across the layers' border, 0.5 px behind the cell's mean.
    const std::vector<Box> boxes = {{-1.0, 0.8, 28.2, 1.6}, {-1.6, 1.4, 29.9, 3.2, 0.3}};
    const DisparityMap d = render(cam, 1.65, boxes);
    check_car_only_with_rule(d, cam, palette, pixel_of(cam, 0.0, 0.8, 28.2),
                             [](GeometryOptions& o) { o.continuity_behind_m = 0.0; });
    // The bus beside the car still continues across the border.
    const auto [u, v] = pixel_of(cam, 1.2, 0.8, 29.9);
    CHECK(class_at(derive_semantics(d, cam, ImageU8{}, palette, {}), palette, u, v) == "building");
    GeometryOptions o;
    o.continuity_behind_m = -1.0;
    CHECK_THROWS_WITH(o.validate(), Catch::Contains("continuity_behind_m"));
    o = GeometryOptions{};
    o.continuity_behind_px = 0.0;
    CHECK_THROWS_WITH(o.validate(), Catch::Contains("continuity_behind_px"));
}

TEST_CASE("a crown's blend into the bus behind is not the top of the car between them",
          "[geometry]") {
    const StereoCamera cam = kitti_rig();
    const auto palette = cloud_analysis::load_palette("cityscapes");
    // A car's back at 26 m, a bus's back at 29.5 m behind it, a tree's crown at 24 m hanging to
    // 2.3 m above the road. The matcher blends the crown's disparity (16.2 px) into the bus's
    // (13.2 px) over the 8 rows below the crown: those rows pass the car's 14-15 px at
    // 2.2-2.25 m, in the car's cells.
    const std::vector<Box> boxes =
        with_car_from_behind({{-1.6, 1.4, 29.5, 3.2, 0.3}, {-2.5, 2.5, 24.0, 6.0, 2.3}}, 26.0);
    DisparityMap d = render(cam, 1.65, boxes);
    const double fb = cam.fx_px * cam.baseline_m, crown = fb / 24.0, bus = fb / 29.5;
    for (int u = 0; u < d.width_px; ++u) {
        for (int v = 1; v + 8 < d.height_px; ++v) {
            const auto at = [&](int row) -> float& {
                return d.disparity_px[static_cast<std::size_t>(row) * d.width_px + u];
            };
            if (std::abs(double{at(v - 1)} - crown) > 0.01 ||
                std::abs(double{at(v)} - bus) > 0.01) {
                continue;
            }
            for (int r = 0; r < 8; ++r) {
                at(v + r) = static_cast<float>(crown + (bus - crown) * (r + 1) / 9.0);
            }
            break;
        }
    }
    // Tops from the blended pixels too: the car is 2.2 m tall or more, no car.
    check_car_only_with_rule(d, cam, palette, pixel_of(cam, 0.0, 0.6, 26.0),
                             [](GeometryOptions& o) { o.blend_step_px = 1e5; });
    GeometryOptions o;
    o.blend_rows = 0;
    CHECK_THROWS_WITH(o.validate(), Catch::Contains("blend_rows"));
    o = GeometryOptions{};
    o.blend_step_px = -1.0;
    CHECK_THROWS_WITH(o.validate(), Catch::Contains("blend_step_px"));
}

TEST_CASE("a surface 2.5 m behind a car, seen only above its roof, is not the car's top",
          "[geometry]") {
    const StereoCamera cam = kitti_rig();
    const auto palette = cloud_analysis::load_palette("cityscapes");
    // A car's back at 27.5 m and, 2.5 m beyond its cabin, a face as wide as the cabin and
    // 2.28 m tall: it shows only above the roof, in the car's column bands, one disparity bin
    // beyond the cabin's (linked to it). Its top would make the car 2.28 m tall.
    const std::vector<Box> boxes = with_car_from_behind({{-0.8, 0.6, 30.6, 2.28}}, 27.5);
    const DisparityMap d = render(cam, 1.65, boxes);
    check_car_only_with_rule(d, cam, palette, pixel_of(cam, 0.0, 0.6, 27.5),
                             [](GeometryOptions& o) { o.behind_gap_m = 0.0; });
    GeometryOptions o;
    o.behind_gap_m = -1.0;
    CHECK_THROWS_WITH(o.validate(), Catch::Contains("behind_gap_m"));
}

TEST_CASE("the lowest edge of a crown a metre before a car, in the car's cells, is not its top",
          "[geometry]") {
    const StereoCamera cam = kitti_rig();
    const auto palette = cloud_analysis::load_palette("cityscapes");
    // A car's back at 27.7 m (14.05 px) under a crown at 26.2 m (14.9 px) hanging to 2.27 m:
    // the crown's lowest row falls in the cells of the car's back, 0.8 px ahead of their mean,
    // and its column runs on up into the crown above the layers' border.
    const std::vector<Box> boxes = with_car_from_behind({{-2.5, 2.5, 26.2, 6.0, 2.27}}, 27.7);
    const DisparityMap d = render(cam, 1.65, boxes);
    check_car_only_with_rule(d, cam, palette, pixel_of(cam, 0.0, 0.6, 27.7),
                             [](GeometryOptions& o) { o.foot_ahead_px = 1e5; });
    GeometryOptions o;
    o.foot_ahead_px = 0.0;
    CHECK_THROWS_WITH(o.validate(), Catch::Contains("foot_ahead_px"));
}

TEST_CASE("a car cut by the matcher's left border is a car, though narrower than one",
          "[geometry]") {
    const StereoCamera cam = kitti_rig();
    const auto palette = cloud_analysis::load_palette("cityscapes");
    // The back of a car 5 m ahead on the left (x -4.0 to -3.0, 1.45 m high) and a person-wide
    // board of the same height in the open (x 1.0 to 1.8, 8 m). Nothing left of column d (its
    // disparity) has a match in the right view: 0.68 m of the car's back shows.
    const std::vector<Box> boxes = {{-4.0, -3.0, 5.0, 1.45}, {1.0, 1.8, 8.0, 1.45}};
    DisparityMap d = render(cam, 1.65, boxes);
    for (int v = 0; v < d.height_px; ++v) {
        for (int u = 0; u < d.width_px; ++u) {
            float& x = d.disparity_px[static_cast<std::size_t>(v) * d.width_px + u];
            if (x > 0.0f && u < x) x = kNoDisparity;
        }
    }
    const SceneGeometry g = derive_semantics(d, cam, ImageU8{}, palette, {});
    REQUIRE(g.ground.found);
    const auto [cu, cv] = pixel_of(cam, -3.3, 0.7, 5.0);
    CHECK(class_at(g, palette, cu, cv) == "car");
    const auto [pu, pv] = pixel_of(cam, 1.4, 0.7, 8.0);
    CHECK(class_at(g, palette, pu, pv) == "person");
}

TEST_CASE("a car-sized surface within the matcher's left border band at its depth is no car",
          "[geometry]") {
    const StereoCamera cam = kitti_rig();
    const auto palette = cloud_analysis::load_palette("cityscapes");
    // A board 1.45 m high at 14.4 m (27 px of disparity) by the image's left edge, as the
    // matcher's guesses for a facade the right camera cannot see there put it: its columns end
    // 35 px in, all within 8 columns of the border at its depth (offset + d). The same board
    // 80 px farther right is a car's back, the board's height and tops alike.
    const double z = 14.4;
    const double x_at_35 = (35.0 - cam.cx_px) * z / cam.fx_px;
    const double x_at_115 = (115.0 - cam.cx_px) * z / cam.fx_px;
    const auto classed = [&](double x1) {
        const DisparityMap d = render(cam, 1.65, {{x1 - 1.8, x1, z, 1.45}});
        const SceneGeometry g = derive_semantics(d, cam, ImageU8{}, palette, {});
        REQUIRE(g.ground.found);
        const auto [u, v] = pixel_of(cam, x1 - 0.3, 0.9, z);
        return class_at(g, palette, u, v);
    };
    CHECK(classed(x_at_35) != "car");
    CHECK(classed(x_at_115) == "car");
}

TEST_CASE("a car under a tree's crown stays a car, a facade runs on above the car's layer",
          "[geometry]") {
    const StereoCamera cam = kitti_rig();
    const auto palette = cloud_analysis::load_palette("cityscapes");
    // The crown hangs 1.5 m above the roof at the car's own depth: one u-disparity cell holds
    // both, in different layers. The wall beside it (a facade's foot) is continuous.
    const std::vector<Box> boxes =
        with_car_from_behind({{-2.5, 2.5, 12.3, 6.0, 3.0},  // a crown, 3 to 6 m up
                              {4.0, 12.0, 12.0, 6.0}},      // a facade
                             12.0);
    const SceneGeometry g = derive_semantics(render(cam, 1.65, boxes), cam, ImageU8{}, palette, {});
    REQUIRE(g.ground.found);
    const auto [cu, cv] = pixel_of(cam, 0.0, 0.8, 12.0);
    CHECK(class_at(g, palette, cu, cv) == "car");
    const auto [tu, tv] = pixel_of(cam, 0.0, 4.5, 12.3);
    CHECK(class_at(g, palette, tu, tv) != "car");
    for (const double up : {0.8, 2.0, 4.0}) {
        const auto [fu, fv] = pixel_of(cam, 8.0, up, 12.0);
        CHECK(class_at(g, palette, fu, fv) == "building");
    }
}

TEST_CASE("a car parked against a wall keeps its back a car and the wall a building",
          "[geometry]") {
    const StereoCamera cam = kitti_rig();
    const auto palette = cloud_analysis::load_palette("cityscapes");
    // The wall stands 0.3 m behind the car's cabin, across the whole view. The car's back, a
    // flat top 1.7 m wide, is as thin and level as a wall's: too narrow for one.
    const std::vector<Box> boxes = with_car_from_behind({{-8.0, 8.0, 10.9, 4.0}}, 10.0);
    const auto [cu, cv] = pixel_of(cam, 0.0, 0.8, 10.0);
    const auto [wu, wv] = pixel_of(cam, 4.0, 3.0, 10.9);
    for (const char* segmentation : {"columns", "clusters"}) {
        GeometryOptions o;
        o.segmentation = segmentation;
        const SceneGeometry g =
            derive_semantics(render(cam, 1.65, boxes), cam, ImageU8{}, palette, o);
        INFO(segmentation);
        CHECK(class_at(g, palette, cu, cv) == "car");
        CHECK(class_at(g, palette, wu, wv) == "building");
    }
}

TEST_CASE("kerbside clutter level along more than a car's width is not a car, though deep",
          "[geometry]") {
    const StereoCamera cam = kitti_rig();
    const auto palette = cloud_analysis::load_palette("cityscapes");
    // Bins, a post box and a wall's foot on the sidewalk, one height (1.2 m), staggered over
    // 1.4 m of depth: too deep across for a wall, as level as one, and longer than a car's
    // back. A car's tops run from its boot to its roof.
    std::vector<Box> boxes;
    for (int k = 0; k < 9; ++k) {
        boxes.push_back(
            {3.5 + 0.45 * k, 3.95 + 0.45 * k, 15.0 + 0.35 * (4 - std::abs(k - 4)), 1.2});
    }
    boxes = with_car_from_behind(std::move(boxes), 15.0);
    const SceneGeometry g = derive_semantics(render(cam, 1.65, boxes), cam, ImageU8{}, palette, {});
    REQUIRE(g.ground.found);
    for (const auto& [x, z] : {std::pair{3.7, 15.0}, std::pair{5.5, 16.4}, std::pair{7.3, 15.0}}) {
        const auto [u, v] = pixel_of(cam, x, 0.6, z);
        INFO("x " << x);
        CHECK(class_at(g, palette, u, v) == "static");
    }
    const auto [cu, cv] = pixel_of(cam, 0.0, 0.8, 15.0);
    CHECK(class_at(g, palette, cu, cv) == "car");
}

TEST_CASE("a garden wall with pillars is a wall, not a car", "[geometry]") {
    const StereoCamera cam = kitti_rig();
    const auto palette = cloud_analysis::load_palette("cityscapes");
    // A wall 1 m high and 3 m long at 15 m with three pillars 0.3 m higher: its tops vary by
    // the pillars' 0.3 m, more than a plain wall's, less than a car's.
    const std::vector<Box> boxes = with_car_from_behind({{4.0, 7.0, 15.0, 1.0},
                                                         {4.0, 4.45, 15.0, 1.3},
                                                         {5.3, 5.75, 15.0, 1.3},
                                                         {6.55, 7.0, 15.0, 1.3}},
                                                        15.0);
    const SceneGeometry g = derive_semantics(render(cam, 1.65, boxes), cam, ImageU8{}, palette, {});
    REQUIRE(g.ground.found);
    for (const double x : {4.9, 6.1}) {
        const auto [u, v] = pixel_of(cam, x, 0.6, 15.0);
        INFO("x " << x);
        CHECK(class_at(g, palette, u, v) == "wall");
    }
    const auto [cu, cv] = pixel_of(cam, 0.0, 0.8, 15.0);
    CHECK(class_at(g, palette, cu, cv) == "car");
}

TEST_CASE("the green pixels of a car segment are vegetation, by their window's mean colour",
          "[geometry]") {
    const StereoCamera cam = kitti_rig();
    const auto palette = cloud_analysis::load_palette("cityscapes");
    const std::vector<Box> boxes = with_car_from_behind({}, 10.0);
    // A grey image with a bush over the car's left half: green leaves every other column, dark
    // shadows between them (not green one by one, green on average).
    ImageU8 left;
    left.width_px = cam.width_px;
    left.height_px = cam.height_px;
    left.channels = 3;
    left.data.assign(static_cast<std::size_t>(left.width_px) * left.height_px * 3, 120);
    const auto [bu0, bv0] = pixel_of(cam, -1.0, 1.0, 10.0);
    const auto [bu1, bv1] = pixel_of(cam, -0.1, 0.4, 10.0);
    for (int v = bv0; v <= bv1; ++v) {
        for (int u = bu0; u <= bu1; ++u) {
            auto* p = left.data.data() + (static_cast<std::size_t>(v) * left.width_px + u) * 3;
            const bool leaf = u % 2 == 0;
            p[0] = leaf ? 60 : 40;
            p[1] = leaf ? 140 : 40;
            p[2] = leaf ? 40 : 40;
        }
    }
    const SceneGeometry g = derive_semantics(render(cam, 1.65, boxes), cam, left, palette, {});
    REQUIRE(g.ground.found);
    const auto [gu, gv] = pixel_of(cam, -0.6, 0.7, 10.0);
    CHECK(class_at(g, palette, gu | 1, gv) == "vegetation");  // a shadow column
    const auto [cu, cv] = pixel_of(cam, 0.5, 0.7, 10.0);
    CHECK(class_at(g, palette, cu, cv) == "car");
}

TEST_CASE(
    "a car-shaped surface is a car by its horizontal edges, not with upright or "
    "isotropic texture",
    "[geometry]") {
    const StereoCamera cam = kitti_rig();
    const auto palette = cloud_analysis::load_palette("cityscapes");
    const DisparityMap d = render(cam, 1.65, with_car_from_behind({}, 10.0));
    const auto [cu, cv] = pixel_of(cam, 0.0, 0.8, 10.0);
    const auto class_with = [&](int (*grey)(int, int), const GeometryOptions& o) {
        const ImageU8 left = textured(cam, -1.0, 0.0, 0.8, 1.5, 10.0, grey);
        return class_at(derive_semantics(d, cam, left, palette, o), palette, cu, cv);
    };
    CHECK(class_with(horizontal_stripes, {}) == "car");
    CHECK(class_with(upright_stripes, {}) == "static");
    CHECK(class_with(speckle, {}) == "static");
    GeometryOptions off;
    off.car_min_edge_share = 0.0;
    CHECK(class_with(speckle, off) == "car");
    // Without an image, or on a plain one, nothing speaks against the car.
    CHECK(class_at(derive_semantics(d, cam, ImageU8{}, palette, {}), palette, cu, cv) == "car");
    const ImageU8 plain = textured(cam, -1.0, 0.0, 0.8, 1.5, 10.0, [](int, int) { return 120; });
    CHECK(class_at(derive_semantics(d, cam, plain, palette, {}), palette, cu, cv) == "car");
    // The segment table reports the share.
    const SceneGeometry g = derive_semantics(
        d, cam, textured(cam, -1.0, 0.0, 0.8, 1.5, 10.0, upright_stripes), palette, {});
    const auto s = g.segment_of_pixel[static_cast<std::size_t>(cv) * cam.width_px + cu];
    REQUIRE(s >= 0);
    CHECK(g.segments[static_cast<std::size_t>(s)].horizontal_edges < 0.1);
}

TEST_CASE("edges are read at the rig's scale: pixel speckle averages out over wider boxes",
          "[geometry]") {
    const StereoCamera cam = kitti_rig();
    const auto palette = cloud_analysis::load_palette("cityscapes");
    const DisparityMap d = render(cam, 1.65, with_car_from_behind({}, 10.0));
    const auto [cu, cv] = pixel_of(cam, 0.0, 0.8, 10.0);
    // Horizontal stripes 8 px high under strong upright stripes 2 px wide, which 2 x 2 boxes
    // turn into a 1 px alternation a 3x3 Sobel does not see.
    const ImageU8 left = textured(cam, -1.0, 0.0, 0.8, 1.5, 10.0, [](int u, int v) {
        return ((v / 8) % 2 ? 100 : 150) + ((u / 2) % 2 ? 60 : -60);
    });
    GeometryOptions o;
    CHECK(class_at(derive_semantics(d, cam, left, palette, o), palette, cu, cv) == "static");
    o.edge_step_px = 2;
    CHECK(class_at(derive_semantics(d, cam, left, palette, o), palette, cu, cv) == "car");
}

TEST_CASE("a surface whose depth grows with height below a car's waist is no car, a car's back is",
          "[geometry]") {
    const StereoCamera cam = kitti_rig();
    const auto palette = cloud_analysis::load_palette("cityscapes");
    // Beside a car's back at 12 m, a bank 3 m wide (x 2-5 m) rising 1 in 4 from 15 m to 21 m,
    // 1.5 m high (a staircase of 75 steps, every other one 1 cm higher: not level as a wall). A
    // vehicle's lower body stands upright.
    std::vector<Box> bank;
    for (int k = 0; k < 75; ++k) {
        bank.push_back({2.0, 5.0, 15.0 + 0.08 * k, 0.02 * (k + 1) + (k % 2) * 0.01});
    }
    const DisparityMap d = render(cam, 1.65, with_car_from_behind(bank, 12.0));
    const auto bank_px = pixel_of(cam, 3.5, 1.0, 18.9);
    const auto car_px = pixel_of(cam, 0.0, 0.5, 12.0);
    GeometryOptions off;
    off.car_max_lean = 0.0;
    const SceneGeometry without = derive_semantics(d, cam, ImageU8{}, palette, off);
    REQUIRE(class_at(without, palette, bank_px.first, bank_px.second) == "car");
    const SceneGeometry g = derive_semantics(d, cam, ImageU8{}, palette, {});
    CHECK(class_at(g, palette, bank_px.first, bank_px.second) == "static");
    CHECK(class_at(g, palette, car_px.first, car_px.second) == "car");
    // The segments say how far each car candidate leans.
    const auto lean_at = [&](std::pair<int, int> px) {
        const auto s = g.segment_of_pixel[static_cast<std::size_t>(px.second) * cam.width_px +
                                          static_cast<std::size_t>(px.first)];
        REQUIRE(s >= 0);
        return g.segments[static_cast<std::size_t>(s)].lean;
    };
    CHECK(lean_at(bank_px) > 3.0);
    CHECK(std::abs(lean_at(car_px)) < 0.3);
}

TEST_CASE("a car merged with upright clutter beside it keeps its own bands as car", "[geometry]") {
    const StereoCamera cam = kitti_rig();
    const auto palette = cloud_analysis::load_palette("cityscapes");
    // Fence posts 2 m wide right beside the car, as deep and as high as its back: one segment,
    // most of its gradient energy in upright edges.
    const DisparityMap d = render(cam, 1.65, with_car_from_behind({{0.8, 2.8, 10.0, 1.0}}, 10.0));
    ImageU8 left = textured(cam, -1.0, 0.0, 0.8, 1.5, 10.0,
                            [](int, int v) { return (v / 4) % 2 ? 100 : 140; });
    left = textured(cam, 0.85, 0.0, 2.8, 1.0, 10.0, upright_stripes, left);
    const SceneGeometry g = derive_semantics(d, cam, left, palette, {});
    const auto [cu, cv] = pixel_of(cam, -0.5, 0.8, 10.0);
    const auto [fu, fv] = pixel_of(cam, 2.3, 0.8, 10.0);
    REQUIRE(g.segment_of_pixel[static_cast<std::size_t>(cv) * cam.width_px + cu] ==
            g.segment_of_pixel[static_cast<std::size_t>(fv) * cam.width_px + fu]);
    // The whole segment falls short of a car's share: its car bands are found one by one.
    const auto s = g.segment_of_pixel[static_cast<std::size_t>(cv) * cam.width_px + cu];
    CHECK(g.segments[static_cast<std::size_t>(s)].horizontal_edges < 0.3);
    CHECK(class_at(g, palette, cu, cv) == "car");
    CHECK(class_at(g, palette, fu, fv) == "static");
}

TEST_CASE("a wall filling the view or a wrong baseline gives no ground and a warning",
          "[geometry]") {
    StereoCamera cam = kitti_rig();
    const auto palette = cloud_analysis::load_palette("cityscapes");
    const SceneGeometry wall = derive_semantics(render(cam, 1.65, {{-50.0, 50.0, 4.0, 20.0}}), cam,
                                                ImageU8{}, palette, {});
    CHECK_FALSE(wall.ground.found);
    REQUIRE(wall.warnings.size() == 1);
    CHECK_THAT(wall.warnings[0], Catch::Contains("no ground found"));
    const auto sky = cloud_analysis::find_class(palette, "sky");
    CHECK(std::all_of(wall.classes.class_index.begin(), wall.classes.class_index.end(),
                      [&](auto c) { return c == cloud_analysis::kVoidClass || c == sky; }));
    // The same road analysed with six times the baseline lies 9.9 m below the camera.
    const DisparityMap road = render(cam, 1.65, {{-1.0, 0.8, 10.0, 1.5}});
    cam.baseline_m *= 6.0;
    const SceneGeometry wrong = derive_semantics(road, cam, ImageU8{}, palette, {});
    CHECK_FALSE(wrong.ground.found);
    CHECK(wrong.ground.camera_height_m == Approx(9.9).margin(0.1));
    REQUIRE(wrong.warnings.size() == 1);
    CHECK_THAT(wrong.warnings[0], Catch::Contains("baseline"));
    const auto car = cloud_analysis::find_class(palette, "car");
    CHECK(std::count(wrong.classes.class_index.begin(), wrong.classes.class_index.end(), car) == 0);
}

TEST_CASE("semantic scores count equal pixels and per-class IoU", "[geometry]") {
    const auto palette = cloud_analysis::load_palette("cityscapes");
    const auto road = cloud_analysis::find_class(palette, "road");
    const auto car = cloud_analysis::find_class(palette, "car");
    cloud_analysis::ClassImage truth{2, 2, {road, road, car, cloud_analysis::kVoidClass}, 1};
    cloud_analysis::ClassImage estimate{2, 2, {road, car, car, car}, 0};
    const SemanticScore s = score_semantics(estimate, truth, palette, {"road", "car", "sky"});
    CHECK(s.pixels == 3);
    CHECK(s.accuracy == Approx(2.0 / 3.0));
    REQUIRE(s.iou.size() == 3);
    CHECK(s.iou[0].second == Approx(0.5));  // road: 1 both / 2 either
    CHECK(s.iou[1].second == Approx(0.5));  // car: 1 both / 2 either (void pixel not scored)
    CHECK(s.iou[2].second == Approx(-1.0));
    const ImageU8 rgb = colour_classes(estimate, palette);
    CHECK(rgb.channels == 3);
    CHECK(rgb.data[0] == 128);  // road 128, 64, 128
    CHECK(rgb.data[5] == 142);  // car 0, 0, 142
}

TEST_CASE("the per-pixel passes give the same classes and segments on any number of threads",
          "[geometry]") {
    const StereoCamera cam = kitti_rig();
    const auto palette = cloud_analysis::load_palette("cityscapes");
    const std::vector<Box> boxes = with_car_from_behind({{3.5, 12.0, 15.0, 8.0},
                                                         {-4.0, -3.8, 8.0, 4.0},
                                                         {-12.0, -6.0, 14.0, 1.2},
                                                         {-3.0, -1.6, 22.0, 1.4}},
                                                        10.0);
    const DisparityMap d = render(cam, 1.65, boxes);
    // A colour image: random colours over the left half (their window means lie near the
    // green test's bounds), stripes on the car.
    ImageU8 left;
    left.width_px = cam.width_px;
    left.height_px = cam.height_px;
    left.channels = 3;
    left.data.resize(static_cast<std::size_t>(cam.width_px) * cam.height_px * 3);
    for (int v = 0; v < cam.height_px; ++v) {
        for (int u = 0; u < cam.width_px; ++u) {
            auto* p = left.data.data() + (static_cast<std::size_t>(v) * cam.width_px + u) * 3;
            if (u < cam.width_px / 2) {
                p[0] = static_cast<std::uint8_t>(speckle(u, v));
                p[1] = static_cast<std::uint8_t>(std::min(255, speckle(u + 1, v) + 20));
                p[2] = static_cast<std::uint8_t>(speckle(u, v + 1));
            } else {
                p[0] = p[1] = p[2] = static_cast<std::uint8_t>(horizontal_stripes(u, v));
            }
        }
    }
    GeometryOptions one;
    one.threads = 1;
    const SceneGeometry a = derive_semantics(d, cam, left, palette, one);
    REQUIRE(a.ground.found);
    REQUIRE(a.segments.size() >= 4);
    for (const int threads : {2, 3, 7}) {
        GeometryOptions o;
        o.threads = threads;
        const SceneGeometry b = derive_semantics(d, cam, left, palette, o);
        CHECK(b.classes.class_index == a.classes.class_index);
        REQUIRE(b.segments.size() == a.segments.size());
        for (std::size_t k = 0; k < a.segments.size(); ++k) {
            CHECK(b.segments[k].class_index == a.segments[k].class_index);
            CHECK(b.segments[k].top_m == a.segments[k].top_m);
            CHECK(b.segments[k].horizontal_edges == a.segments[k].horizontal_edges);
            CHECK(b.segments[k].green == a.segments[k].green);
        }
    }
}

TEST_CASE("geometry options name the bad field", "[geometry]") {
    // Each bad value, set on the defaults, and the field the error names.
    const std::vector<std::pair<std::function<void(GeometryOptions&)>, std::string>> bad = {
        {[](GeometryOptions& o) { o.column_bin_px = 0; }, "column_bin_px"},
        {[](GeometryOptions& o) { o.max_camera_height_m = 0.1; }, "max_camera_height_m"},
        {[](GeometryOptions& o) { o.layer_height_m = o.car_max_height_m; }, "layer_height_m"},
        {[](GeometryOptions& o) { o.min_face_share = 1.0; }, "min_face_share"},
        {[](GeometryOptions& o) { o.green_window_px = -1; }, "green_window_px"},
        {[](GeometryOptions& o) { o.car_min_edge_share = 1.0; }, "car_min_edge_share"},
        {[](GeometryOptions& o) { o.car_max_lean = -1.0; }, "car_max_lean"},
        {[](GeometryOptions& o) { o.vehicle_piece_m = 0.0; }, "vehicle_piece_m"},
        {[](GeometryOptions& o) { o.edge_window_m = 0.0; }, "edge_window_m"},
        {[](GeometryOptions& o) { o.edge_step_px = 0; }, "edge_step_px"},
        {[](GeometryOptions& o) { o.segmentation = "stixels"; }, "segmentation"},
        {[](GeometryOptions& o) { o.threads = 0; }, "threads"},
    };
    for (const auto& [set, field] : bad) {
        GeometryOptions o;
        set(o);
        INFO(field);
        CHECK_THROWS_WITH(o.validate(), Catch::Contains(field));
    }
}
