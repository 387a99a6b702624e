#include <catch2/catch.hpp>

#include "cloud_analysis/evaluation/labels_2d.hpp"

#include "../kitti_rig.hpp"

using namespace cloud_analysis;

namespace {

scene_schema::CameraIntrinsics camera() { return test_rigs::kitti_intrinsics(); }

/// A car standing on the road 1.65 m below the camera, facing along the road.
scene_schema::Entity car(std::string id, double x, double z, std::string cls = "car") {
    scene_schema::Entity e;
    e.id = std::move(id);
    e.class_name = std::move(cls);
    e.x = x;
    e.y = 1.65 - 0.75;
    e.z = z;
    e.theta = 1.5708;
    e.W = 1.8;
    e.H = 1.5;
    e.L = 4.2;
    return e;
}

/// The box a person would draw around an entity: its projection.
Label2d label_of(const scene_schema::Entity& e, std::string type = "car") {
    FrameLabels2d none;
    const FrameScore2d s = score_frame_2d({e}, camera(), none, {});
    REQUIRE(s.entities.size() == 1);
    Label2d l;
    l.type = std::move(type);
    l.category = *category_of_type(l.type);
    l.box_px = s.entities[0].box_px;
    return l;
}

}  // namespace

TEST_CASE("2D labels: types and classes fall into vehicle, person and cyclist", "[labels_2d]") {
    CHECK(category_of_type("Van") == Category2d::vehicle);
    CHECK(category_of_type("truck") == Category2d::vehicle);
    CHECK(category_of_type("Pedestrian") == Category2d::person);
    CHECK(category_of_type("Cyclist") == Category2d::cyclist);
    CHECK_FALSE(category_of_type("DontCare"));
    CHECK(category_of_class("caravan") == Category2d::vehicle);
    CHECK(category_of_class("rider") == Category2d::cyclist);
    CHECK_FALSE(category_of_class("vegetation"));
}

TEST_CASE("2D labels: the JSON file reads frames, objects and don't-care regions", "[labels_2d]") {
    const Labels2d l = parse_labels_2d(
        R"({"image_width": 1242, "image_height": 375, "frames": [
          {"frame": "a", "objects": [{"type": "car", "box": [10, 20, 50, 60], "occluded": 1,
            "truncated": 0.25, "track": "t1"}], "dont_care": [[0, 0, 5, 5]]},
          {"frame": "b"}]})",
        "mem");
    REQUIRE(l.frames.size() == 2);
    CHECK(l.width_px == 1242);
    REQUIRE(l.find("a") != nullptr);
    CHECK(l.find("c") == nullptr);
    const Label2d& o = l.find("a")->objects.at(0);
    CHECK(o.category == Category2d::vehicle);
    CHECK(o.occluded == 1);
    CHECK(o.truncated == Approx(0.25));
    CHECK(o.track == "t1");
    CHECK(o.box_px[2] == 50.0);
    CHECK(l.find("a")->dont_care.size() == 1);
    CHECK(l.find("b")->objects.empty());
}

TEST_CASE("2D labels: a malformed JSON file is refused naming the rule and the file",
          "[labels_2d]") {
    auto refuses = [](const char* text, const char* what) {
        CHECK_THROWS_WITH(parse_labels_2d(text, "f.json"),
                          Catch::Contains(what) && Catch::EndsWith("(f.json)"));
    };
    refuses("[1, 2]", "needs a \"frames\" list");
    refuses("{\"frames\": [{\"objects\": []}]}", "needs a \"frame\" id");
    refuses(R"({"frames": [{"frame": "a", "objects": [{"type": "tree", "box": [0, 0, 1, 1]}]}]})",
            "unknown type \"tree\"");
    refuses(R"({"frames": [{"frame": "a", "objects": [{"type": "car", "box": [5, 0, 1, 1]}]}]})",
            "u1 > u0");
    refuses(R"({"frames": [{"frame": "a", "objects": [{"type": "car", "box": [0, 0, 1]}]}]})",
            "[u0, v0, u1, v1]");
    refuses(R"({"frames": [{"frame": "a", "objects": [{"type": "car", "box": [0, 0, 1, 1],
            "occluded": 7}]}]})",
            "\"occluded\" is 0, 1, 2 or 3");
    refuses(R"({"frames": [{"frame": "a"}, {"frame": "a"}]})", "labelled twice");
    refuses("{\"frames\": [", "not JSON");
}

TEST_CASE("2D labels: KITTI label_2 gives objects and don't-care regions", "[labels_2d]") {
    const auto kitti = parse_kitti_labels(
        "Car 0.00 1 1.85 387.63 181.54 423.81 203.12 1.67 1.87 3.69 -16.53 2.39 58.49 1.57\n"
        "Tree 0.00 0 0 1 1 2 2 1 1 1 0 0 5 0\n"
        "DontCare -1 -1 -10 503.89 169.71 590.61 190.13 -1 -1 -1 -1000 -1000 -1000 -10\n",
        "mem");
    const FrameLabels2d f = labels_2d_from_kitti(kitti, "000001");
    REQUIRE(f.objects.size() == 1);
    CHECK(f.objects[0].occluded == 1);
    CHECK(f.objects[0].box_px[0] == Approx(387.63));
    REQUIRE(f.dont_care.size() == 1);
    CHECK(f.dont_care[0][2] == Approx(590.61));
}

TEST_CASE("2D labels: an entity whose projection is the label is found, others are false",
          "[labels_2d]") {
    const auto seen = car("car-1", 2.0, 15.0);
    FrameLabels2d labels;
    labels.frame = "f";
    labels.objects.push_back(label_of(seen));
    const auto hedge = car("car-2", -6.0, 20.0);  // nothing labelled there
    const auto far = car("car-3", -6.0, 45.0);    // beyond 30 m: not counted
    const FrameScore2d s = score_frame_2d({seen, hedge, far}, camera(), labels, {});
    const Counts2d& v = s.counts[static_cast<int>(Category2d::vehicle)];
    CHECK(v.owed == 1);
    CHECK(v.found == 1);
    CHECK(v.counted == 2);
    CHECK(v.correct == 1);
    CHECK(v.false_entities() == 1);
    CHECK(v.ignored == 1);
    CHECK(v.precision() == Approx(0.5));
    CHECK(s.missed.empty());
}

TEST_CASE("2D labels: a box shifted by half its width no longer matches", "[labels_2d]") {
    const auto e = car("car-1", 2.0, 15.0);
    FrameLabels2d labels;
    Label2d l = label_of(e);
    const double w = l.box_px[2] - l.box_px[0];
    l.box_px[0] += 0.5 * w;
    l.box_px[2] += 0.5 * w;
    labels.objects.push_back(l);
    const FrameScore2d s = score_frame_2d({e}, camera(), labels, {});
    CHECK(s.counts[0].found == 0);
    CHECK(s.counts[0].false_entities() == 1);
    CHECK(s.missed.size() == 1);
}

TEST_CASE("2D labels: a partly hidden label matches the whole projected box that covers it",
          "[labels_2d]") {
    const auto e = car("car-1", 2.0, 15.0);
    Label2d l = label_of(e);
    // Only the right 40 % is seen: IoU 0.4.
    l.box_px[0] = l.box_px[2] - 0.4 * (l.box_px[2] - l.box_px[0]);
    FrameLabels2d labels;
    labels.objects.push_back(l);
    CHECK(score_frame_2d({e}, camera(), labels, {}).counts[0].found == 0);
    labels.objects[0].occluded = 1;
    CHECK(score_frame_2d({e}, camera(), labels, {}).counts[0].found == 1);
}

TEST_CASE(
    "2D labels: small, hidden and truncated labels are not owed and their match is not "
    "counted",
    "[labels_2d]") {
    const auto e = car("car-1", 2.0, 15.0);
    Match2dOptions o;
    for (int variant = 0; variant < 3; ++variant) {
        Label2d l = label_of(e);
        if (variant == 0) o.min_height_px = 500.0;
        if (variant == 1) l.occluded = 2;
        if (variant == 2) l.truncated = 0.8;
        FrameLabels2d labels;
        labels.objects.push_back(l);
        const FrameScore2d s = score_frame_2d({e}, camera(), labels, o);
        CHECK(s.counts[0].owed == 0);
        CHECK(s.counts[0].counted == 0);
        CHECK(s.counts[0].ignored == 1);
        o = {};
    }
}

TEST_CASE("2D labels: one label takes one entity, a second on it is false", "[labels_2d]") {
    const auto e = car("car-1", 2.0, 15.0);
    auto twin = e;
    twin.id = "car-2";
    twin.z += 0.3;
    FrameLabels2d labels;
    labels.objects.push_back(label_of(e));
    const FrameScore2d s = score_frame_2d({e, twin}, camera(), labels, {});
    CHECK(s.counts[0].correct == 1);
    CHECK(s.counts[0].false_entities() == 1);
}

TEST_CASE("2D labels: an entity inside a don't-care region is not counted", "[labels_2d]") {
    const auto e = car("car-1", 2.0, 15.0);
    FrameLabels2d labels;
    labels.dont_care.push_back(label_of(e).box_px + Eigen::Vector4d(-5, -5, 5, 5));
    const FrameScore2d s = score_frame_2d({e}, camera(), labels, {});
    CHECK(s.counts[0].counted == 0);
    CHECK(s.counts[0].ignored == 1);
}

TEST_CASE("2D labels: categories never match across", "[labels_2d]") {
    const auto rider = car("rider-1", 2.0, 15.0, "rider");
    FrameLabels2d labels;
    labels.objects.push_back(label_of(car("x", 2.0, 15.0)));  // a vehicle label
    const FrameScore2d s = score_frame_2d({rider}, camera(), labels, {});
    CHECK(s.counts[static_cast<int>(Category2d::vehicle)].found == 0);
    CHECK(s.counts[static_cast<int>(Category2d::cyclist)].false_entities() == 1);
}

TEST_CASE("2D labels: a camera without a focal length is refused", "[labels_2d]") {
    CHECK_THROWS_AS(score_frame_2d({}, scene_schema::CameraIntrinsics{}, {}, {}),
                    std::invalid_argument);
    Match2dOptions o;
    o.min_iou = 0.0;
    CHECK_THROWS_WITH(o.validate(), Catch::Contains("min_iou"));
}
