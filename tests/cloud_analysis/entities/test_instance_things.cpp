#include <algorithm>
#include <cmath>
#include <cstdint>
#include <vector>

#include <catch2/catch.hpp>

#include "cloud_analysis/entities/candidate.hpp"
#include "cloud_analysis/entities/extract.hpp"
#include "stereoscene/support/angles.hpp"

using stereoscene::support::kPi;

using namespace cloud_analysis;

namespace {

constexpr int kSide = 2000;  // pixel grid: kSide x kSide, f = 500 px, principal point centred

Palette test_palette() {
    Palette p;
    p.name = "test";
    p.classes = {{"road", 7, false, {128, 64, 128}}, {"car", 26, true, {0, 0, 142}}};
    return p;
}

/// A cloud on a pinhole grid with an instance id per pixel.
struct Scene {
    LabeledCloud cloud;
    Scene() {
        cloud.width_px = kSide;
        cloud.height_px = kSide;
        cloud.instance_id.assign(static_cast<std::size_t>(kSide) * kSide, 0);
        for (float x = -6.0f; x <= 10.0f; x += 0.25f) {
            for (float z = 3.0f; z <= 40.0f; z += 0.25f) add({x, 1.65f, z}, 0, 0);
        }
    }
    void add(const Eigen::Vector3f& p, std::uint16_t cls, std::uint32_t id) {
        const long u = std::clamp(std::lround(500.0 * p.x() / p.z() + kSide / 2), 0L, kSide - 1L);
        const long v = std::clamp(std::lround(500.0 * p.y() / p.z() + kSide / 2), 0L, kSide - 1L);
        const auto pixel = static_cast<std::uint32_t>(v * kSide + u);
        cloud.xyz_m.push_back(p);
        cloud.colour.push_back({0, 0, 0});
        cloud.class_index.push_back(cls);
        cloud.pixel.push_back(pixel);
        if (id != 0) cloud.instance_id[pixel] = id;
    }
    /// The left side (x = x_side) and rear of a car parked along z from z0, 4.2 m, 1.5 m high.
    void add_car(float x_side, float z0, std::uint32_t id) {
        for (float y = 0.15f; y <= 1.65f; y += 0.05f) {
            for (float z = z0; z <= z0 + 4.2f; z += 0.05f) add({x_side, y, z}, 1, id);
            for (float x = x_side; x <= x_side + 1.8f; x += 0.05f) add({x, y, z0}, 1, id);
        }
    }
    std::vector<scene_schema::Entity> cars(bool with_instances) const {
        LabeledCloud c = cloud;
        if (!with_instances) c.instance_id.clear();
        ExtractOptions o;
        o.classes = load_class_config(std::string(STEREOSCENE_SOURCE_DIR) +
                                      "/assets/classes/entity_config.json");
        std::vector<scene_schema::Entity> out;
        for (const auto& e : extract_entities(c, test_palette(), StereoCamera{}, o).entities) {
            if (e.class_name == "car") out.push_back(e);
        }
        std::sort(out.begin(), out.end(), [](const auto& a, const auto& b) { return a.z < b.z; });
        return out;
    }
};

}  // namespace

TEST_CASE("two cars parked bumper to bumper are two things when the instance image says so",
          "[entities][instances]") {
    Scene s;
    s.add_car(3.0f, 8.0f, 0x1a01);
    s.add_car(3.0f, 12.2f, 0x1a02);  // touching: no gap for the clustering to find
    const auto cars = s.cars(true);
    REQUIRE(cars.size() == 2);
    CHECK(cars[0].extra.at("instance_id") == 0x1a01);
    CHECK(cars[1].extra.at("instance_id") == 0x1a02);
    for (std::size_t k = 0; k < 2; ++k) {
        CHECK(cars[k].z == Approx(10.1 + 4.2 * static_cast<double>(k)).margin(0.3));
        CHECK(cars[k].L == Approx(4.2).margin(0.3));
        CHECK(std::abs(std::sin(cars[k].theta)) > std::sin(80.0 * kPi / 180.0));
    }
}

TEST_CASE("car pixels without an instance id are clustered as without an instance image",
          "[entities][instances]") {
    Scene s;
    s.add_car(3.0f, 8.0f, 0x1a01);
    s.add_car(-4.8f, 20.0f, 0);
    const auto cars = s.cars(true);
    REQUIRE(cars.size() == 2);
    CHECK(cars[0].extra.at("instance_id") == 0x1a01);
    CHECK_FALSE(cars[1].extra.contains("instance_id"));
    CHECK(cars[1].z == Approx(22.1).margin(0.4));
    // Without the instance image the same scene gives the same cars, none with an id.
    const auto plain = s.cars(false);
    REQUIRE(plain.size() == 2);
    for (const auto& e : plain) CHECK_FALSE(e.extra.contains("instance_id"));
}

TEST_CASE("an object's pixels that took a farther surface's disparity do not stretch its box",
          "[entities][instances]") {
    Scene s;
    s.add_car(3.0f, 8.0f, 0x1a01);
    // A tenth of its pixels matched 6-9 m behind it along their rays (a mask drawn past its
    // outline, a window onto the street behind).
    for (float y = 0.15f; y <= 1.65f; y += 0.05f) {
        for (float z = 8.0f; z <= 8.6f; z += 0.05f) {
            const float scale = (z + 7.5f) / z;
            s.add({3.0f * scale, y * scale, (z + 7.5f)}, 1, 0x1a01);
        }
    }
    const auto cars = s.cars(true);
    REQUIRE(cars.size() == 1);
    CHECK(cars[0].L == Approx(4.2).margin(0.3));
    CHECK(cars[0].z == Approx(10.1).margin(0.3));
}

TEST_CASE("something standing in front of an object inside its outline is not its surface",
          "[entities][instances]") {
    // A car parked on the right, rear at 12 m, and a post 0.8 m wide 0.45 m in front of its rear
    // face, in the middle of it, labelled as the car (labels bled over it). Rows every 2 cm, so
    // that every image row holds the rear on both sides of the post.
    Scene s;
    constexpr float z0 = 12.0f, z_post = 11.55f, x_post = 3.4f, post_w = 0.8f;
    // Whether the post hides (x, z): the post spans the rays of slope x / z over its width.
    const auto behind_post = [&](float x, float z) {
        return x / z >= x_post / z_post && x / z <= (x_post + post_w) / z_post;
    };
    for (float y = 0.15f; y <= 1.65f; y += 0.02f) {
        for (float z = z0; z <= z0 + 4.2f; z += 0.05f) s.add({3.0f, y, z}, 1, 0x1a01);
        for (float x = 3.0f; x <= 4.8f; x += 0.02f) {
            if (!behind_post(x, z0)) s.add({x, y, z0}, 1, 0x1a01);
        }
        const float y_post = y * z_post / z0;  // the same image row as the rear's point
        for (float x = x_post; x <= x_post + post_w; x += 0.02f) {
            s.add({x, y_post, z_post}, 1, 0x1a01);
        }
    }
    const auto cars = s.cars(true);
    REQUIRE(cars.size() == 1);
    // Its box starts at its rear, not at the post.
    CHECK(cars[0].z - cars[0].L / 2.0 == Approx(z0).margin(0.15));
    CHECK(cars[0].z == Approx(z0 + 2.1).margin(0.2));
}

TEST_CASE("the densest range window keeps the surface and drops what lies beyond its extent",
          "[entities][instances]") {
    std::vector<Eigen::Vector3f> pts;
    instances::Indices all;
    for (int k = 0; k < 100; ++k) pts.emplace_back(0.0f, 0.0f, 10.0f + 0.03f * k);  // 10-13 m
    for (int k = 0; k < 20; ++k) pts.emplace_back(0.0f, 0.0f, 20.0f + 0.1f * k);    // 20-22 m
    for (std::size_t i = 0; i < pts.size(); ++i) all.push_back(i);
    const instances::Indices kept = instances::densest_range_window(pts, all, 5.0, 10);
    REQUIRE(kept.size() == 100);
    CHECK(kept.front() == 0);
    CHECK(kept.back() == 99);
    // Fewer than min_points in the window: everything is kept.
    CHECK(instances::densest_range_window(pts, all, 5.0, 150).size() == pts.size());
}

TEST_CASE("cars parked side by side seen front-on at an angle head along their end faces' normal",
          "[entities][instances]") {
    Scene s;
    // Noses at x = 4.35 (cars 4.3 m long heading along x), 2.4 m apart along z: each shows its
    // front and bonnet only, 35 degrees off the optical axis for the first.
    for (int k = 0; k < 3; ++k) {
        const float zc = 7.0f + 2.4f * static_cast<float>(k);
        const auto id = static_cast<std::uint32_t>(0x1a01 + k);
        for (float z = zc - 0.9f; z <= zc + 0.9f; z += 0.05f) {
            for (float h = 0.3f; h <= 0.9f; h += 0.05f) s.add({4.35f, 1.65f - h, z}, 1, id);
            for (float x = 4.35f; x <= 5.35f; x += 0.05f) s.add({x, 1.65f - 0.9f, z}, 1, id);
        }
    }
    const auto cars = s.cars(true);
    REQUIRE(cars.size() == 3);
    for (std::size_t k = 0; k < 3; ++k) {
        CHECK(std::abs(std::sin(cars[k].theta)) < std::sin(10.0 * kPi / 180.0));
        CHECK(cars[k].z == Approx(7.0 + 2.4 * static_cast<double>(k)).margin(0.3));
        CHECK(cars[k].x == Approx(6.5).margin(0.4));
    }
}
