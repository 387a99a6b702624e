#include <string>
#include <vector>

#include <catch2/catch.hpp>

#include "cloud_analysis/evaluation/diagnosis.hpp"
#include "stereoscene/support/angles.hpp"

using stereoscene::support::kHalfPi;

namespace {

using namespace cloud_analysis;
using scene_schema::Entity;

/// A box heading along z (theta -pi/2): length along the row, as parked cars.
Entity box(const std::string& id, const std::string& cls, double x, double z, double L,
           double W = 1.8) {
    Entity e;
    e.id = id;
    e.class_name = cls;
    e.x = x;
    e.y = 0.85;
    e.z = z;
    e.L = L;
    e.W = W;
    e.H = 1.5;
    e.theta = -kHalfPi;
    return e;
}

const Diagnosis* find(const std::vector<Diagnosis>& all, const std::string& id,
                      const std::string& kind) {
    for (const auto& d : all) {
        if (d.id == id && d.kind == kind) return &d;
    }
    return nullptr;
}

bool contains(const std::string& text, const std::string& part) {
    return text.find(part) != std::string::npos;
}

}  // namespace

TEST_CASE("diagnosis names the merge, the under-covered car and what a phantom stands on",
          "[evaluate][diagnosis]") {
    // Two cars bumper to bumper at z 10 and 14.7 boxed as one 9.4 m box centred between them;
    // a third car boxed 1.5 m short; a car box over a tree.
    const std::vector<Entity> reference = {box("car-1", "car", 5.0, 10.0, 4.5),
                                           box("car-2", "car", 5.0, 14.7, 4.5),
                                           box("car-3", "car", -5.0, 12.0, 4.5),
                                           box("vegetation-1", "vegetation", -5.0, 25.0, 2.6, 2.6),
                                           box("road-1", "road", 0.0, 20.0, 80.0, 12.0)};
    const std::vector<Entity> estimate = {box("car-1", "car", 5.0, 12.35, 9.4),
                                          box("car-2", "car", -5.0, 10.75, 2.0),
                                          box("car-3", "car", -5.0, 25.0, 2.0)};
    const EntityEvaluation ev = evaluate_entities(reference, estimate, EntityEvalOptions{});
    const auto why = diagnose_entities(reference, estimate, ev);
    const Diagnosis* merged = find(why, "car-1", "merged");
    REQUIRE(merged);
    CHECK(contains(merged->reason, "merged with car-2 into car-1"));
    CHECK(find(why, "car-2", "merged"));
    const Diagnosis* spans = find(why, "car-1", "spans");
    REQUIRE(spans);
    CHECK(contains(spans->reason, "9.4 x 1.8 m box spans car-"));
    const Diagnosis* under = find(why, "car-3", "under-covered");
    REQUIRE(under);
    CHECK(contains(under->reason, "car-2 covers 44 % of it"));
    const Diagnosis* phantom = find(why, "car-3", "phantom");
    REQUIRE(phantom);
    CHECK(contains(phantom->reason, "phantom over vegetation vegetation-1"));
    CHECK(why.size() == 5);
}

TEST_CASE("diagnosis of KITTI cars: a merged car, a duplicate and a phantom over the image",
          "[evaluate][diagnosis]") {
    // GT cars as point rows along z at x 5: car 1 at z 8-12, car 2 at z 12.5-16.5.
    const auto gt_car = [](int instance, double z0) {
        GtCar c;
        c.instance = instance;
        for (int i = 0; i <= 40; ++i)
            c.points_m.emplace_back(5.0f, 0.5f, static_cast<float>(z0 + 0.1 * i));
        c.pixel_count = c.points_m.size();
        c.centroid_m = Eigen::Vector3d(5.0, 0.5, z0 + 2.0);
        return c;
    };
    CarMatchOptions options;
    options.min_gt_pixels = 10;
    const std::vector<GtCar> gt = {gt_car(1, 8.0), gt_car(2, 12.5)};
    // One box over both cars (matched to one), one box over nothing.
    const std::vector<Entity> entities = {box("car-1", "car", 5.0, 12.25, 7.6),
                                          box("car-2", "car", -5.0, 20.0, 4.2)};
    const CarEvaluation ev = evaluate_cars(entities, gt, options);
    REQUIRE(ev.matches.size() == 1);
    InstanceImage image;
    image.width_px = 100;
    image.height_px = 50;
    image.values.assign(100 * 50, 21 << 8);
    image.label_name.assign(256, "");
    image.label_name[21] = "vegetation";
    StereoCamera camera;
    camera.fx_px = camera.fy_px = 50.0;
    camera.cx_px = 50.0;
    camera.cy_px = 25.0;
    const auto why = diagnose_cars(entities, gt, ev, options, &image, &camera);
    REQUIRE(why.size() == 2);
    CHECK(why[0].kind == "merged");
    CHECK(contains(why[0].reason, "into car-1"));
    CHECK(why[1].id == "car-2");
    CHECK(why[1].kind == "phantom");
    CHECK(contains(why[1].reason, "vegetation 100 %"));
}
