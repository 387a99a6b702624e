#include <algorithm>
#include <cstdint>
#include <functional>
#include <tuple>
#include <utility>
#include <vector>

#include <catch2/catch.hpp>

#include "cloud_analysis/cloud/instances.hpp"

using namespace cloud_analysis;

namespace {

/// road (stuff, labelId 7) and car (thing, labelId 26).
Palette palette() {
    Palette p;
    p.name = "test";
    p.classes = {{"road", 7, false, {128, 64, 128}}, {"car", 26, true, {0, 0, 142}}};
    return p;
}

/// A 4 x 1 class image: road, car, car, car.
ClassImage classes() {
    ClassImage c;
    c.width_px = 4;
    c.height_px = 1;
    c.class_index = {0, 1, 1, 1};
    return c;
}

IdImage ids(std::vector<std::uint16_t> values) {
    IdImage image;
    image.ids.width_px = static_cast<int>(values.size());
    image.ids.height_px = 1;
    image.ids.values = std::move(values);
    return image;
}

IdImage colours(std::vector<std::uint8_t> rgb, int channels = 3) {
    IdImage image;
    image.colour.width_px = static_cast<int>(rgb.size()) / channels;
    image.colour.height_px = 1;
    image.colour.channels = channels;
    image.colour.data = std::move(rgb);
    return image;
}

}  // namespace

TEST_CASE("KITTI instance ids give each car pixel its object and stuff pixels none",
          "[instances]") {
    const std::uint16_t road = 7 << 8, car1 = (26 << 8) | 1, car2 = (26 << 8) | 2;
    for (const auto encoding : {InstanceEncoding::kAuto, InstanceEncoding::kKitti}) {
        const InstanceMap m =
            decode_instances(ids({road, car1, car1, car2}), encoding, classes(), palette());
        CHECK(m.encoding == InstanceEncoding::kKitti);
        CHECK(m.id == std::vector<std::uint32_t>{0, car1, car1, car2});
        CHECK(m.objects == 2);
        CHECK(m.class_agreement_permille == 1000);
    }
    // A car pixel whose id is a car's without an instance number keeps no object.
    CHECK(decode_instances(ids({road, 26 << 8, car1, car1}), InstanceEncoding::kAuto, classes(),
                           palette())
              .id == std::vector<std::uint32_t>{0, 0, car1, car1});
}

TEST_CASE("Cityscapes instance ids are told from KITTI ones by the classes they give",
          "[instances]") {
    const InstanceMap m = decode_instances(ids({7, 26001, 26001, 26000 + 7}),
                                           InstanceEncoding::kAuto, classes(), palette());
    CHECK(m.encoding == InstanceEncoding::kCityscapes);
    CHECK(m.id == std::vector<std::uint32_t>{0, 26001, 26001, 26007});
    // Renderers leave stuff pixels at 0: that says nothing and does not count against them.
    const InstanceMap rendered = decode_instances(ids({0, (26 << 8) | 3, (26 << 8) | 3, 0}),
                                                  InstanceEncoding::kAuto, classes(), palette());
    CHECK(rendered.encoding == InstanceEncoding::kKitti);
    CHECK(rendered.objects == 1);
}

TEST_CASE("colour instance images take each colour as an object of its pixels' class",
          "[instances]") {
    // Black road, one red car over three pixels of which the first is road (label bleed).
    ClassImage c = classes();
    c.class_index = {0, 1, 1, 1};
    const InstanceMap m = decode_instances(colours({255, 0, 0, 255, 0, 0, 255, 0, 0, 0, 0, 255}),
                                           InstanceEncoding::kAuto, c, palette());
    CHECK(m.encoding == InstanceEncoding::kColour);
    // The road pixel under the red object keeps no object: the object is a car.
    CHECK(m.id == std::vector<std::uint32_t>{0, 0xff0000u, 0xff0000u, 0x0000ffu});
    CHECK(m.objects == 2);
}

TEST_CASE("bad instance images are refused with the reason", "[instances]") {
    const std::uint16_t car = (26 << 8) | 1;
    CHECK_THROWS_WITH(
        decode_instances(ids({car, car, car}), InstanceEncoding::kAuto, classes(), palette()),
        Catch::Contains("instance image is 3x1, semantic image is 4x1"));
    CHECK_THROWS_WITH(decode_instances(colours({0, 0, 0, 1, 1, 1, 2, 2, 2, 3, 3, 3}),
                                       InstanceEncoding::kKitti, classes(), palette()),
                      Catch::Contains("8-bit samples where 16-bit kitti ids are expected"));
    CHECK_THROWS_WITH(
        decode_instances(ids({0, car, car, car}), InstanceEncoding::kColour, classes(), palette()),
        Catch::Contains("16-bit ids where 8-bit RGB colours are expected"));
    CHECK_THROWS_WITH(decode_instances(colours({0, 0, 0, 9, 9, 9}, 1), InstanceEncoding::kAuto,
                                       ClassImage{6, 1, {0, 1, 1, 1, 1, 1}, 0}, palette()),
                      Catch::Contains("8-bit single-channel"));
    // An object id on a stuff class.
    CHECK_THROWS_WITH(decode_instances(ids({(7 << 8) | 4, car, car, car}), InstanceEncoding::kKitti,
                                       classes(), palette()),
                      Catch::Contains("object ids on stuff class 'road' (1 pixels)"));
    CHECK_THROWS_WITH(decode_instances(colours({9, 9, 9, 0, 0, 0, 0, 0, 0, 0, 0, 0}),
                                       InstanceEncoding::kAuto, classes(), palette()),
                      Catch::Contains("object colour 9,9,9 lies on stuff class 'road'"));
    // Classes that are not the semantic image's: another frame, encoding or palette.
    CHECK_THROWS_WITH(decode_instances(ids({car, 7 << 8, 7 << 8, 7 << 8}), InstanceEncoding::kKitti,
                                       classes(), palette()),
                      Catch::Contains("match the semantic image on 0 %"));
    // No classes to decode against.
    CHECK_THROWS_WITH(
        decode_instances(ids({car}), InstanceEncoding::kAuto, ClassImage{}, palette()),
        Catch::Contains("semantic image"));
}

TEST_CASE("instance encodings are named", "[instances]") {
    for (const char* name : {"auto", "kitti", "cityscapes", "colour"}) {
        CHECK(instance_encoding_name(parse_instance_encoding(name)) == name);
    }
    CHECK_THROWS_WITH(parse_instance_encoding("rgb"), Catch::Contains("auto, kitti"));
}

namespace {

/// One image row of 24 columns: columns 0-19 take their object id (0: none) and disparity (px)
/// from `column`, columns 20-23 are background without an object at disparity 5 (80 m).
struct Row {
    InstanceMap instances;
    DisparityMap disparity;
};
Row one_row(const std::function<std::pair<std::uint32_t, float>(int)>& column) {
    Row r;
    r.instances.width_px = r.disparity.width_px = 24;
    r.instances.height_px = r.disparity.height_px = 1;
    r.instances.id.assign(24, 0);
    r.disparity.disparity_px.assign(24, 5.0f);
    for (int u = 0; u < 20; ++u) {
        std::tie(r.instances.id[static_cast<std::size_t>(u)],
                 r.disparity.disparity_px[static_cast<std::size_t>(u)]) = column(u);
    }
    return r;
}

/// mark_object_outlines of the row at 400 px m (disparity 40: 10 m, 10: 40 m), step 0.8 m,
/// 4 columns.
std::vector<std::uint8_t> outlines(const Row& r) {
    std::vector<std::uint8_t> edge;
    mark_object_outlines(edge, r.instances, r.disparity, MatchBorder{400.0, 0.0}, 0.8, 4);
    return edge;
}

}  // namespace

TEST_CASE("an object's pixels beside a nearer object's outline are marked as a depth edge",
          "[instances]") {
    // Object 1 (near, 10 m) over columns 0-9, object 2 (far, 40 m) over 10-19.
    Row r = one_row([](int u) { return u < 10 ? std::pair{1u, 40.0f} : std::pair{2u, 10.0f}; });
    const std::vector<std::uint8_t> edge = outlines(r);
    REQUIRE(edge.size() == 24);
    for (int u = 0; u < 24; ++u) {
        INFO("column " << u);
        // The far object's first four columns; never the near object, never the background.
        CHECK(edge[static_cast<std::size_t>(u)] == (u >= 10 && u < 14 ? 1 : 0));
    }
    // Objects at one depth (within the step) mark nothing.
    std::fill(r.disparity.disparity_px.begin(), r.disparity.disparity_px.begin() + 20, 40.0f);
    const std::vector<std::uint8_t> none = outlines(r);
    CHECK(std::count(none.begin(), none.end(), 1) == 0);
}

TEST_CASE("an object's pixels beside a nearer surface of no object are marked as a depth edge",
          "[instances]") {
    // Object 1 at 40 m over columns 0-19 but for a trunk of no object at 10 m over columns 8-9.
    Row r = one_row([](int u) {
        return u == 8 || u == 9 ? std::pair{0u, 40.0f} : std::pair{1u, 10.0f};
    });
    const std::vector<std::uint8_t> edge = outlines(r);
    REQUIRE(edge.size() == 24);
    for (int u = 0; u < 24; ++u) {
        INFO("column " << u);
        // Four columns of the object on each side of the trunk; never the trunk or background.
        CHECK(edge[static_cast<std::size_t>(u)] == ((u >= 4 && u < 8) || (u >= 10 && u < 14)));
    }
    // A surface of no object behind the object (farther by more than the step) marks nothing.
    r.disparity.disparity_px[8] = r.disparity.disparity_px[9] = 8.0f;
    const std::vector<std::uint8_t> none = outlines(r);
    CHECK(std::count(none.begin(), none.end(), 1) == 0);
}
