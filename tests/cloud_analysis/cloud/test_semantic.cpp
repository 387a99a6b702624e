#include <catch2/catch.hpp>

#include "cloud_analysis/cloud/semantic.hpp"

using namespace cloud_analysis;

TEST_CASE("the bundled palettes load and map KITTI's Cityscapes colours to labelIds",
          "[semantic]") {
    const Palette city = load_palette("cityscapes");
    REQUIRE(city.name == "cityscapes");
    const auto car = find_colour(city, Rgb{0, 0, 142});
    REQUIRE(car != kVoidClass);
    CHECK(city.classes[car].name == "car");
    CHECK(city.classes[car].id == 26);
    CHECK(city.classes[car].thing);
    const auto road = find_class(city, "road");
    REQUIRE(road != kVoidClass);
    CHECK(city.classes[road].id == 7);
    CHECK_FALSE(city.classes[road].thing);
    CHECK(find_colour(city, Rgb{0, 0, 0}) == kVoidClass);
    CHECK(load_palette("carla").classes.size() > 10);
    const Palette thesis = load_palette("thesis");
    CHECK(thesis.classes[find_colour(thesis, Rgb{255, 0, 255})].name == "car");
}

TEST_CASE("a palette with a duplicated colour is refused naming the class", "[semantic]") {
    const char* text = R"({"name":"x","classes":[
        {"name":"a","id":1,"colour":[1,2,3]},{"name":"b","id":2,"colour":[1,2,3]}]})";
    REQUIRE_THROWS_WITH(parse_palette(text, "p.json"),
                        Catch::Contains("p.json: /classes/1/colour"));
    REQUIRE_THROWS_WITH(
        parse_palette(R"({"name":"x","classes":[{"name":"a","id":-1,"colour":[0,0,0]}]})", "q"),
        Catch::Contains("/classes/0/id"));
}

TEST_CASE("pixels take the class of their colour and unknown colours count as void", "[semantic]") {
    const Palette city = load_palette("cityscapes");
    ImageU8 img;
    img.width_px = 3;
    img.height_px = 2;
    img.channels = 3;
    img.data = {0, 0, 142, 0, 0, 142, 128, 64, 128, 1, 2, 3, 70, 130, 180, 1, 2, 3};
    const ClassImage classes = classify_pixels(img, city);
    REQUIRE(classes.class_index.size() == 6);
    CHECK(city.classes[classes.class_index[0]].name == "car");
    CHECK(city.classes[classes.class_index[1]].name == "car");
    CHECK(city.classes[classes.class_index[2]].name == "road");
    CHECK(classes.class_index[3] == kVoidClass);
    CHECK(city.classes[classes.class_index[4]].name == "sky");
    CHECK(classes.void_pixels == 2);
}
