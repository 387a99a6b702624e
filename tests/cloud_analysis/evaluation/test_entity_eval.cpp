#include <cmath>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include <catch2/catch.hpp>
#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>

#include "cloud_analysis/evaluation/entity_eval.hpp"
#include "cloud_analysis/evaluation/kitti_labels.hpp"
#include "stereoscene/support/angles.hpp"

#include "../kitti_rig.hpp"

namespace {

using cloud_analysis::EntityEvalOptions;
using scene_schema::Entity;

using stereoscene::support::kPi;

Entity box(const std::string& cls, double x, double z, double theta, double W = 2.0, double L = 4.0,
           double H = 1.5, double y = 0.9) {
    Entity e;
    e.id = cls + "-" + std::to_string(static_cast<int>(x * 10)) + "-" +
           std::to_string(static_cast<int>(z * 10));
    e.class_name = cls;
    e.x = x;
    e.y = y;
    e.z = z;
    e.theta = theta;
    e.W = W;
    e.L = L;
    e.H = H;
    return e;
}

}  // namespace

TEST_CASE("identical boxes have BEV and 3D IoU 1", "[entity_eval]") {
    const Entity a = box("car", 1.0, 12.0, 0.3);
    CHECK(cloud_analysis::bev_iou(a, a) == Approx(1.0).margin(1e-12));
    CHECK(cloud_analysis::iou_3d(a, a) == Approx(1.0).margin(1e-12));
}

TEST_CASE("disjoint boxes have IoU 0", "[entity_eval]") {
    const Entity a = box("car", 0.0, 10.0, 0.0);
    const Entity b = box("car", 10.0, 10.0, 0.7);
    CHECK(cloud_analysis::bev_iou(a, b) == 0.0);
    CHECK(cloud_analysis::iou_3d(a, b) == 0.0);
    // Same footprint, no overlap in y: BEV IoU 1, 3D IoU 0.
    const Entity above = box("car", 0.0, 10.0, 0.0, 2.0, 4.0, 1.5, -2.0);
    CHECK(cloud_analysis::bev_iou(a, above) == Approx(1.0));
    CHECK(cloud_analysis::iou_3d(a, above) == 0.0);
}

TEST_CASE("a 4 x 2 m box turned 90 degrees about its centre has IoU 1/3", "[entity_eval]") {
    // Overlap is the 2 x 2 m square: 4 / (8 + 8 - 4).
    const Entity a = box("car", 3.0, 15.0, 0.4);
    const Entity b = box("car", 3.0, 15.0, 0.4 + kPi / 2.0);
    CHECK(cloud_analysis::bev_iou(a, b) == Approx(1.0 / 3.0).epsilon(1e-9));
    CHECK(cloud_analysis::iou_3d(a, b) == Approx(1.0 / 3.0).epsilon(1e-9));
}

TEST_CASE("a box shifted by half its length has BEV IoU 1/3 and half its height 3D IoU 1/7",
          "[entity_eval]") {
    const Entity a = box("car", 0.0, 10.0, 0.0);  // length along x
    const Entity b = box("car", 2.0, 10.0, 0.0);
    CHECK(cloud_analysis::bev_iou(a, b) == Approx(1.0 / 3.0).epsilon(1e-9));
    const Entity c = box("car", 2.0, 10.0, 0.0, 2.0, 4.0, 1.5, 0.9 + 0.75);
    // Volume overlap 4 * 0.75 = 3 of 12 + 12 - 3.
    CHECK(cloud_analysis::iou_3d(a, c) == Approx(3.0 / 21.0).epsilon(1e-9));
}

TEST_CASE("footprint corners follow the heading (cos theta, -sin theta)", "[entity_eval]") {
    // theta = -pi/2 heads along +z: the length (4 m) spans z.
    const auto c = cloud_analysis::footprint_corners(box("car", 0.0, 10.0, -kPi / 2.0));
    double zmin = 1e9, zmax = -1e9, xmin = 1e9, xmax = -1e9;
    for (const auto& p : c) {
        xmin = std::min(xmin, p.x());
        xmax = std::max(xmax, p.x());
        zmin = std::min(zmin, p.y());
        zmax = std::max(zmax, p.y());
    }
    CHECK(zmax - zmin == Approx(4.0));
    CHECK(xmax - xmin == Approx(2.0));
}

TEST_CASE("heading error is taken modulo pi", "[entity_eval]") {
    CHECK(cloud_analysis::heading_error_rad(0.1, 0.1 + kPi) == Approx(0.0).margin(1e-12));
    CHECK(cloud_analysis::heading_error_rad(-kPi / 2.0, kPi / 2.0) == Approx(0.0).margin(1e-12));
    CHECK(cloud_analysis::heading_error_rad(0.0, kPi / 2.0) == Approx(kPi / 2.0));
    CHECK(cloud_analysis::heading_error_rad(0.0, 3.0 * kPi / 4.0) == Approx(kPi / 4.0));
    CHECK(cloud_analysis::heading_error_rad(-0.2, 0.3) == Approx(0.5));
}

TEST_CASE("distance bins are 0-10, 10-20, 20-30, 30-50 m of bird's-eye range", "[entity_eval]") {
    CHECK(cloud_analysis::distance_bin(0.0) == 0);
    CHECK(cloud_analysis::distance_bin(9.99) == 0);
    CHECK(cloud_analysis::distance_bin(10.0) == 1);
    CHECK(cloud_analysis::distance_bin(29.9) == 2);
    CHECK(cloud_analysis::distance_bin(30.0) == 3);
    CHECK(cloud_analysis::distance_bin(49.9) == 3);
    CHECK(cloud_analysis::distance_bin(50.0) == -1);
    CHECK(cloud_analysis::distance_bin_name(3) == "30-50");
    CHECK(cloud_analysis::distance_bin_name(4) == "all");
    // Range is hypot(x, z): a box at x = 8, z = 8 is 11.3 m away.
    CHECK(cloud_analysis::distance_bin(cloud_analysis::bev_range_m(box("car", 8.0, 8.0, 0))) == 1);
}

TEST_CASE("one missing and one spurious car give precision and recall 2/3", "[entity_eval]") {
    const std::vector<Entity> reference = {box("car", -2.0, 8.0, 0.0), box("car", 2.0, 15.0, 0.0),
                                           box("car", 0.0, 25.0, 0.0)};
    // Two found (one 0.5 m off), the third missed, one car where none is.
    const std::vector<Entity> estimate = {box("car", -2.0, 8.5, 0.1), box("car", 2.0, 15.0, 0.0),
                                          box("car", 6.0, 25.0, 0.0)};
    const auto ev = cloud_analysis::evaluate_entities(reference, estimate, EntityEvalOptions{});
    const auto s = ev.within("car", 30.0);
    CHECK(s.reference == 3);
    CHECK(s.matched == 2);
    CHECK(s.missed == 1);
    CHECK(s.spurious == 1);
    CHECK(s.recall() == Approx(2.0 / 3.0));
    CHECK(s.precision() == Approx(2.0 / 3.0));
    CHECK(cloud_analysis::median(s.centre_errors_m) == Approx(0.25));
    REQUIRE(ev.missed.size() == 1);
    CHECK(ev.missed[0] == 2);
    REQUIRE(ev.spurious.size() == 1);
    CHECK(ev.spurious[0] == 2);
    // Per bin: the missed car is in 20-30, the found ones in 0-10 and 10-20.
    REQUIRE(ev.classes.size() == 1);
    CHECK(ev.classes[0].bins[0].matched == 1);
    CHECK(ev.classes[0].bins[1].matched == 1);
    CHECK(ev.classes[0].bins[2].missed == 1);
    CHECK(ev.classes[0].bins[2].spurious == 1);
}

TEST_CASE("matching is one-to-one, per class and greedy by centre distance", "[entity_eval]") {
    const std::vector<Entity> reference = {box("car", 0.0, 10.0, 0.0),
                                           box("person", 0.0, 10.0, 0.0, 0.6, 0.6, 1.7)};
    // Two car estimates near one car: the nearer matches, the other is spurious; no person.
    const std::vector<Entity> estimate = {box("car", 0.0, 11.0, 0.0), box("car", 0.0, 10.2, 0.0)};
    const auto ev = cloud_analysis::evaluate_entities(reference, estimate, EntityEvalOptions{});
    REQUIRE(ev.matches.size() == 1);
    CHECK(ev.matches[0].estimate == 1);
    CHECK(ev.within("car", 30.0).spurious == 1);
    CHECK(ev.within("person", 30.0).recall() == 0.0);
}

TEST_CASE("a stuff entity lying on a reference car counts against stuff on things",
          "[entity_eval]") {
    const std::vector<Entity> reference = {box("car", 0.0, 10.0, 0.0)};
    const std::vector<Entity> estimate = {
        box("car", 0.0, 10.0, 0.0),
        box("building", 0.3, 10.0, 0.0, 1.0, 1.0),       // inside the car: offends
        box("road", 0.0, 20.0, -kPi / 2.0, 8.0, 40.0)};  // large extent: does not
    const auto ev = cloud_analysis::evaluate_entities(reference, estimate, EntityEvalOptions{});
    CHECK(ev.stuff_on_things(30.0) == 1);
    CHECK(ev.within("car", 30.0).spurious == 0);
    cloud_analysis::EvalBars bars;
    bars.max_stuff_on_things = 0;
    const auto missed = cloud_analysis::check_bars(ev, bars);
    REQUIRE(missed.size() == 1);
    CHECK(missed[0].find("--max-stuff-on-things") != std::string::npos);
}

TEST_CASE("bars pass on a perfect estimate and name each bar missed", "[entity_eval]") {
    const std::vector<Entity> reference = {box("car", 0.0, 10.0, 0.0), box("car", 3.0, 20.0, 0.0)};
    cloud_analysis::EvalBars bars;
    bars.require_recall = 1.0;
    bars.max_spurious = 0;
    bars.max_median_centre_error_m = 0.5;
    bars.max_median_heading_error_deg = 10.0;
    bars.min_good_iou_fraction = 0.7;
    auto ev = cloud_analysis::evaluate_entities(reference, reference, EntityEvalOptions{});
    CHECK(cloud_analysis::check_bars(ev, bars).empty());

    // Both 1 m off and turned 30 degrees: centre, heading and IoU bars are missed.
    const std::vector<Entity> poor = {box("car", 0.0, 11.0, kPi / 6.0),
                                      box("car", 3.0, 21.0, kPi / 6.0)};
    ev = cloud_analysis::evaluate_entities(reference, poor, EntityEvalOptions{});
    const auto missed = cloud_analysis::check_bars(ev, bars);
    REQUIRE(missed.size() == 3);
    CHECK(missed[0].find("--max-median-centre-error") != std::string::npos);
    CHECK(missed[1].find("--max-median-heading-error") != std::string::npos);
    CHECK(missed[2].find("--min-good-iou-fraction") != std::string::npos);
}

TEST_CASE("label_2 lines become entities with the centre half a height above KITTI's y",
          "[kitti_labels]") {
    const std::string text =
        "Car 0.00 0 -1.58 587.01 173.33 614.12 200.12 1.65 1.67 3.64 -0.65 1.71 46.70 -1.59\n"
        "\n"
        "DontCare -1 -1 -10 503.89 169.71 590.61 190.13 -1 -1 -1 -1000 -1000 -1000 -10\n"
        "Pedestrian 0.00 0 -0.20 712.40 143.00 810.73 307.92 1.89 0.48 1.20 1.84 1.47 8.41 "
        "0.01 0.87\n";
    const auto labels = cloud_analysis::parse_kitti_labels(text, "test");
    REQUIRE(labels.size() == 3);
    CHECK_FALSE(labels[0].score.has_value());
    REQUIRE(labels[2].score.has_value());
    const auto entities = cloud_analysis::entities_from_kitti_labels(labels);
    REQUIRE(entities.size() == 2);  // DontCare ignored
    CHECK(entities[0].class_name == "car");
    CHECK(entities[0].class_id == 26);
    CHECK(entities[0].y == Approx(1.71 - 1.65 / 2.0));
    CHECK(entities[0].H == Approx(1.65));
    CHECK(entities[0].W == Approx(1.67));
    CHECK(entities[0].L == Approx(3.64));
    CHECK(entities[0].theta == Approx(-1.59));
    CHECK(entities[1].class_name == "person");
    CHECK(entities[1].confidence == Approx(0.87));
}

TEST_CASE("a malformed label_2 line is refused naming the line", "[kitti_labels]") {
    CHECK_THROWS_WITH(cloud_analysis::parse_kitti_labels("Car 0 0 0 1 2 3\n", "f.txt"),
                      Catch::Contains("line 1") && Catch::Contains("f.txt"));
    CHECK_THROWS_WITH(
        cloud_analysis::parse_kitti_labels("Car 0 0 0 1 2 3 4 1.5 x 4 0 1 10 0\n", "f.txt"),
        Catch::Contains("column 10"));
}

TEST_CASE("exported labels read back as a reference give IoU 1", "[kitti_labels]") {
    const scene_schema::CameraIntrinsics cam = test_rigs::kitti_intrinsics();
    std::vector<Entity> ours = {box("car", -2.5, 12.25, -1.57, 1.8, 4.2, 1.5, 0.9),
                                box("person", 3.0, 9.5, 0.0, 0.6, 0.5, 1.75, 0.775),
                                box("road", 0.0, 20.0, -1.57, 8.0, 40.0, 0.2, 1.65)};
    std::vector<cloud_analysis::KittiLabel> labels;
    for (const auto& e : ours) {
        if (cloud_analysis::kitti_type_of_class(e.class_name)) {
            labels.push_back(cloud_analysis::kitti_label_from_entity(e, &cam));
        }
    }
    REQUIRE(labels.size() == 2);  // road has no KITTI type
    CHECK(labels[0].type == "Car");
    CHECK(labels[0].y == Approx(0.9 + 0.75));
    CHECK(labels[0].alpha == Approx(-1.57 - std::atan2(-2.5, 12.25)).margin(1e-9));
    // The car is in front of the camera and inside the image: a real 2D box.
    CHECK(labels[0].bbox[0] > 0.0);
    CHECK(labels[0].bbox[2] > labels[0].bbox[0]);
    CHECK(labels[0].bbox[3] > labels[0].bbox[1]);

    const auto back = cloud_analysis::entities_from_kitti_labels(cloud_analysis::parse_kitti_labels(
        cloud_analysis::format_kitti_labels(labels), "round trip"));
    REQUIRE(back.size() == 2);
    ours.pop_back();
    const auto ev = cloud_analysis::evaluate_entities(back, ours, EntityEvalOptions{});
    REQUIRE(ev.matches.size() == 2);
    for (const auto& m : ev.matches) {
        CHECK(m.bev_iou == Approx(1.0).margin(1e-9));
        CHECK(m.iou_3d == Approx(1.0).margin(1e-9));
    }
}

TEST_CASE("without a camera the exported 2D box is -1", "[kitti_labels]") {
    const auto l = cloud_analysis::kitti_label_from_entity(box("car", 0.0, 10.0, 0.0), nullptr);
    CHECK(l.bbox[0] == -1.0);
    CHECK(l.bbox[3] == -1.0);
    const auto behind = box("car", 0.0, -10.0, 0.0);
    scene_schema::CameraIntrinsics cam;
    cam.fx_px = cam.fy_px = 700.0;
    CHECK(cloud_analysis::kitti_label_from_entity(behind, &cam).bbox[0] == -1.0);
}

TEST_CASE("the exported alpha equals KITTI's own on a label_2 line", "[kitti_labels]") {
    // KITTI object training 000001: Car alpha 1.85 at x -16.53, z 58.49, rotation_y 1.57.
    const auto labels = cloud_analysis::parse_kitti_labels(
        "Car 0.00 0 1.85 387.63 181.54 423.81 203.12 1.67 1.87 3.69 -16.53 2.39 58.49 1.57\n",
        "000001.txt");
    const auto entities = cloud_analysis::entities_from_kitti_labels(labels);
    REQUIRE(entities.size() == 1);
    const auto back = cloud_analysis::kitti_label_from_entity(entities[0], nullptr);
    CHECK(back.alpha == Approx(1.85).margin(0.005));
    CHECK(back.y == Approx(2.39));
}

TEST_CASE("an ignored reference is neither owed nor makes its estimate spurious", "[entity_eval]") {
    const std::vector<Entity> reference = {box("car", 0.0, 10.0, 0.0), box("car", 4.0, 20.0, 0.0),
                                           box("car", -4.0, 20.0, 0.0)};
    // The first is found, the hidden second is found too, the hidden third is not.
    const std::vector<Entity> estimate = {box("car", 0.0, 10.0, 0.0), box("car", 4.0, 20.5, 0.0)};
    const auto ev = cloud_analysis::evaluate_entities(reference, estimate, EntityEvalOptions{},
                                                      {false, true, true});
    const auto s = ev.within("car", 30.0);
    CHECK(s.reference == 1);
    CHECK(s.matched == 1);
    CHECK(s.missed == 0);
    CHECK(s.spurious == 0);
    CHECK(ev.ignored.size() == 2);
    CHECK_THROWS_AS(
        cloud_analysis::evaluate_entities(reference, estimate, EntityEvalOptions{}, {true}),
        std::invalid_argument);
}

TEST_CASE("visible pixels follow the renderer's instance ids: labelId << 8 | ordinal in class",
          "[entity_eval]") {
    // Cars (26) 1 and 2, a person (24) 1; car 2 has 3 pixels, the person 2, car 1 none.
    cv::Mat image(4, 4, CV_16UC1, cv::Scalar(0));
    image.at<std::uint16_t>(0, 0) = 26 << 8 | 2;
    image.at<std::uint16_t>(0, 1) = 26 << 8 | 2;
    image.at<std::uint16_t>(3, 3) = 26 << 8 | 2;
    image.at<std::uint16_t>(1, 1) = 24 << 8 | 1;
    image.at<std::uint16_t>(2, 1) = 24 << 8 | 1;
    image.at<std::uint16_t>(2, 2) = 7 << 8;  // road, no instance
    const auto path = std::filesystem::temp_directory_path() / "stereoscene_visible_test.png";
    REQUIRE(cv::imwrite(path.string(), image));
    std::vector<Entity> reference = {box("car", 0, 10, 0), box("road", 0, 20, 0),
                                     box("person", 1, 9, 0), box("car", 2, 12, 0)};
    reference[0].class_id = 26;
    reference[1].class_id = 7;
    reference[2].class_id = 24;
    reference[3].class_id = 26;
    const auto visible = cloud_analysis::visible_instance_pixels(path, reference);
    std::filesystem::remove(path);
    CHECK(visible == std::vector<std::size_t>{0, 0, 2, 3});
    CHECK_THROWS_WITH(cloud_analysis::visible_instance_pixels(path, reference),
                      Catch::Contains("stereoscene_visible_test.png"));
}

TEST_CASE("visibility records are matched to the reference's things by id", "[entity_eval]") {
    const auto path = std::filesystem::temp_directory_path() / "stereoscene_visibility_test.json";
    std::vector<Entity> reference = {box("car", 0.0, 10.0, 0.0), box("road", 0.0, 20.0, 0.0),
                                     box("car", 4.0, 20.0, 0.0)};
    reference[0].id = "car-1";
    reference[2].id = "car-2";
    {
        std::ofstream out(path);
        out << R"({"width_px": 621, "height_px": 188, "entities": [
            {"id": "car-2", "visible_px": 85, "unoccluded_px": 850},
            {"id": "car-1", "visible_px": 400, "unoccluded_px": 400},
            {"id": "car-9", "visible_px": 0, "unoccluded_px": 0}]})";
    }
    const auto v = cloud_analysis::load_reference_visibility(path, reference, EntityEvalOptions{});
    REQUIRE(v.size() == 3);
    REQUIRE(v[0]);
    CHECK(v[0]->visible_fraction == 1.0);
    CHECK_FALSE(v[1]);  // road is stuff
    REQUIRE(v[2]);
    CHECK(v[2]->visible_px == 85);
    CHECK(v[2]->visible_fraction == Approx(0.1));
    // A thing without a record means the file belongs to another scene.
    reference[0].id = "car-7";
    CHECK_THROWS_WITH(
        cloud_analysis::load_reference_visibility(path, reference, EntityEvalOptions{}),
        Catch::Contains("car-7") && Catch::Contains("stereoscene_visibility_test.json"));
    std::filesystem::remove(path);
    CHECK_THROWS_WITH(
        cloud_analysis::load_reference_visibility(path, reference, EntityEvalOptions{}),
        Catch::Contains("No such file"));
}

TEST_CASE("a car whose subclass is van is a KITTI Van, and a Van label reads back as one",
          "[evaluate][kitti]") {
    Entity van = box("car", 4.9, 18.0, -1.57, 2.0, 5.2, 2.0, 0.6);
    CHECK(cloud_analysis::kitti_label_from_entity(van, nullptr).type == "Car");
    van.extra["subclass"] = "van";
    const auto label = cloud_analysis::kitti_label_from_entity(van, nullptr);
    CHECK(label.type == "Van");
    const auto back = cloud_analysis::entities_from_kitti_labels({label}, {});
    REQUIRE(back.size() == 1);
    CHECK(back[0].class_name == "car");
    CHECK(back[0].extra.value("subclass", "") == "van");
}
