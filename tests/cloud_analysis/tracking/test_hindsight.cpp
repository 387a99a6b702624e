#include <catch2/catch.hpp>

#include <algorithm>
#include <array>
#include <cmath>
#include <filesystem>
#include <random>
#include <string>
#include <vector>

#include "cloud_analysis/tracking/hindsight.hpp"
#include "cloud_analysis/tracking/kalman.hpp"
#include "cloud_analysis/tracking/sequence.hpp"
#include "cloud_analysis/tracking/tracker.hpp"

#include "../kitti_rig.hpp"

using namespace cloud_analysis::tracking;
using scene_schema::Entity;
using scene_schema::EntityDocument;

namespace {

/// A camera at z_m along the world's +z, looking along it.
std::array<double, 12> camera_at(double z_m) { return {1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, z_m}; }

Entity car(const std::string& id, double x, double z, std::optional<std::int64_t> track = {}) {
    Entity e;
    e.id = id;
    e.class_name = "car";
    e.class_id = 26;
    e.x = x;
    e.y = 0.9;
    e.z = z;
    e.theta = -1.5707963;  // parked along the street (length along z)
    e.W = 1.8;
    e.H = 1.5;
    e.L = 4.2;
    e.track_id = track;
    return e;
}

/// A frame seen by KITTI's left camera from `camera_z_m`.
EntityDocument frame_at(double camera_z_m, std::vector<Entity> entities) {
    EntityDocument doc;
    doc.frame.id = "f";
    doc.frame.camera = test_rigs::kitti_intrinsics();
    doc.frame.pose = camera_at(camera_z_m);
    doc.entities = std::move(entities);
    return doc;
}

/// What a frame taken from camera_z_m knows: one still car (track 7) at (3, z) of its camera.
Hindsight known_at(double camera_z_m, double z_m) {
    Hindsight h;
    h.pose = camera_at(camera_z_m);
    StillObject o;
    o.id = 7;
    o.class_name = "car";
    o.class_id = 26;
    o.x_m = 3.0;
    o.y_m = 0.9;
    o.z_m = z_m;
    o.theta_rad = -1.5707963;
    o.W = 1.8;
    o.H = 1.5;
    o.L = 4.2;
    h.still.push_back(o);
    return h;
}

/// A camera driving at 8 m/s for 40 frames (10 a second) past a car parked 30 m ahead of its
/// start that the detector finds only from frame 12 on (20 m away), written to `folder` as
/// f<i>.json with its sequence index; frames from 10 on are `gap_s` later (a gap in time).
scene_schema::SequenceIndex write_parked_car_drive(const std::filesystem::path& folder,
                                                   double gap_s) {
    scene_schema::SequenceIndex index;
    index.id = "parked-car";
    for (int i = 0; i < 40; ++i) {
        const double camera_z = 0.8 * i;
        std::vector<Entity> seen;
        if (i >= 12) seen.push_back(car("car-" + std::to_string(i), 3.0, 30.0 - camera_z));
        const std::string file = "f" + std::to_string(i) + ".json";
        scene_schema::write_file(frame_at(camera_z, seen), folder / file);
        index.frames.push_back({i, file, 0.1 * i + (i >= 10 ? gap_s : 0.0), {}});
    }
    scene_schema::write_sequence_file(index, folder / "sequence.json");
    return index;
}

const Entity* with_track(const EntityDocument& doc, std::int64_t id) {
    const auto it = std::find_if(doc.entities.begin(), doc.entities.end(),
                                 [&](const Entity& e) { return e.track_id == id; });
    return it == doc.entities.end() ? nullptr : &*it;
}

}  // namespace

TEST_CASE("a still object is placed in an earlier frame where the camera's motion puts it",
          "[tracking]") {
    // Known 10 m ahead from z = 20; the earlier frame's camera stood 5 m further back.
    EntityDocument frame = frame_at(15.0, {});
    CHECK(place_still_objects(frame, known_at(20.0, 10.0), TrackerOptions{}) == 1);
    REQUIRE(frame.entities.size() == 1);
    const Entity& e = frame.entities.front();
    CHECK(e.track_id == std::optional<std::int64_t>(7));
    CHECK(e.x == Approx(3.0));
    CHECK(e.z == Approx(15.0));
    CHECK(e.L == Approx(4.2));
    CHECK(e.method == std::optional<std::string>("track hindsight"));
    CHECK(e.point_count == 0);
    // Placed once: a frame that reports it already is left alone.
    CHECK(place_still_objects(frame, known_at(20.0, 10.0), TrackerOptions{}) == 0);
    CHECK(frame.entities.size() == 1);
}

TEST_CASE("an earlier box of the still object's class on it becomes the object's", "[tracking]") {
    // A box of a track that died (a far view merged with a neighbour) 1.2 m off its place, and a
    // car of its own farther along the street.
    EntityDocument frame = frame_at(15.0, {car("car-1", 3.2, 16.2, 99), car("car-2", 3.0, 30.0)});
    CHECK(place_still_objects(frame, known_at(20.0, 10.0), TrackerOptions{}) == 1);
    REQUIRE(frame.entities.size() == 2);
    CHECK(frame.entities[0].track_id == std::optional<std::int64_t>(7));
    CHECK(frame.entities[0].z == Approx(15.0));
    CHECK(frame.entities[0].id == "car-1");
    CHECK_FALSE(frame.entities[1].track_id);
    CHECK(frame.entities[1].z == Approx(30.0));
}

TEST_CASE("a box of another track on a still object is no object of its own", "[tracking]") {
    // Track 7 reported where it stands; a row's box of track 42 sliding along with the camera
    // lies on it; a car of track 43 passes in the next lane.
    Hindsight known = known_at(20.0, 10.0);
    known.moving = {42, 43};
    EntityDocument frame = frame_at(15.0, {car("car-1", 3.0, 15.1, 7), car("car-2", 3.1, 17.0, 42),
                                           car("car-3", -1.5, 15.0, 43)});
    CHECK(place_still_objects(frame, known, TrackerOptions{}) == 0);
    CHECK(frame.entities[0].track_id == std::optional<std::int64_t>(7));
    CHECK_FALSE(frame.entities[1].track_id);
    CHECK_FALSE(frame.entities[1].velocity);
    CHECK(frame.entities[2].track_id == std::optional<std::int64_t>(43));
}

TEST_CASE("a still object is not placed out of view nor across frames of different kinds",
          "[tracking]") {
    // 10 m ahead from z = 20 is behind a camera at z = 35.
    EntityDocument behind = frame_at(35.0, {});
    CHECK(place_still_objects(behind, known_at(20.0, 10.0), TrackerOptions{}) == 0);
    CHECK(behind.entities.empty());
    // A frame without a pose cannot be related to one with a pose.
    EntityDocument no_pose = frame_at(15.0, {});
    no_pose.frame.pose.reset();
    CHECK(place_still_objects(no_pose, known_at(20.0, 10.0), TrackerOptions{}) == 0);
    // A still camera (no poses at all) keeps the object where it is.
    EntityDocument still_camera = frame_at(0.0, {});
    still_camera.frame.pose.reset();
    Hindsight known = known_at(0.0, 10.0);
    known.pose.reset();
    CHECK(place_still_objects(still_camera, known, TrackerOptions{}) == 1);
    REQUIRE(still_camera.entities.size() == 1);
    CHECK(still_camera.entities.front().z == Approx(10.0));
}

TEST_CASE("a parked car is still and a car in traffic is not", "[tracking]") {
    Tracker tracker;
    for (int i = 0; i < 20; ++i) {
        EntityDocument doc =
            frame_at(0.0, {car("parked", 3.0, 20.0), car("driving", -2.0, 10.0 + i)});
        doc.frame.pose.reset();
        tracker.update(doc, 0.1 * i);
    }
    const Hindsight h = hindsight_of(tracker, TrackerOptions{}, std::nullopt);
    REQUIRE(h.still.size() == 1);
    CHECK(h.still.front().x_m == Approx(3.0).margin(0.05));
    CHECK(h.moving.size() == 1);
    CHECK(h.moving.count(h.still.front().id) == 0);
}

TEST_CASE("the still hypothesis tells a far parked car from a slow one near by", "[tracking]") {
    // Measured with the filter's own noise (1.8 m along the ray at 40 m, 0.44 m at 20 m): a car
    // parked 40 m ahead over three seconds is still; one 20 m ahead rolling at 2.5 m/s over a
    // second is not, though the tracker's filter, which lets it accelerate, is not yet sure.
    const KalmanOptions o;
    int still = 0, rolling_still = 0;
    double sq = 0.0;
    const int runs = 200;
    for (int seed = 0; seed < runs; ++seed) {
        std::mt19937 rng(static_cast<unsigned>(seed));
        std::normal_distribution<double> unit(0.0, 1.0);
        StillHypothesis parked(2.0 + 0.35 * unit(rng), 40.0 + 1.76 * unit(rng), o);
        for (int i = 1; i < 30; ++i) {
            parked.predict(0.1);
            parked.update(2.0 + 0.35 * unit(rng), 40.0 + 1.76 * unit(rng));
        }
        still += parked.consistent() ? 1 : 0;
        sq += std::pow(parked.position_m().y() - 40.0, 2);
        StillHypothesis rolling(2.0, 20.0, o);
        for (int i = 1; i < 12; ++i) {
            rolling.predict(0.1);
            rolling.update(2.0 + 0.35 * unit(rng), 20.0 - 0.25 * i + 0.44 * unit(rng));
        }
        rolling_still += rolling.consistent() ? 1 : 0;
    }
    CAPTURE(still, rolling_still, std::sqrt(sq / runs));
    CHECK(still >= 0.95 * runs);
    CHECK(rolling_still <= 0.1 * runs);
    CHECK(std::sqrt(sq / runs) < 1.0);
}

TEST_CASE("track_files reports a parked car in the frames before it was first seen", "[tracking]") {
    // A camera driving at 8 m/s past a car parked 30 m ahead that the detector finds only
    // from frame 12 on (20 m): the frames before it get the car, with the track's id, unless
    // hindsight is off.
    namespace fs = std::filesystem;
    const auto root = fs::temp_directory_path() / "cloud_analysis_tracking_hindsight";
    fs::remove_all(root);
    fs::create_directories(root / "in");
    const scene_schema::SequenceIndex index = write_parked_car_drive(root / "in", 0.0);
    for (const bool hindsight : {true, false}) {
        SequenceTrackOptions o;
        o.hindsight = hindsight;
        const auto out = root / (hindsight ? "on" : "off");
        fs::create_directories(out);
        track_files(index, root / "in" / "sequence.json", out, o, [](const std::string&) {});
        const auto later = scene_schema::read_file(out / "f20.json");
        REQUIRE(later.entities.size() == 1);
        REQUIRE(later.entities.front().track_id);
        const std::int64_t id = *later.entities.front().track_id;
        for (int i = 0; i < 12; ++i) {
            CAPTURE(hindsight, i);
            const auto doc = scene_schema::read_file(out / ("f" + std::to_string(i) + ".json"));
            const Entity* e = with_track(doc, id);
            if (!hindsight) {
                CHECK(e == nullptr);
                continue;
            }
            REQUIRE(e != nullptr);
            CHECK(e->x == Approx(3.0).margin(0.3));
            CHECK(e->z == Approx(30.0 - 0.8 * i).margin(0.3));
        }
    }
    fs::remove_all(root);
}

TEST_CASE("track_files places no still object before a restart of the tracker", "[tracking]") {
    // The same drive with a 2 s gap after frame 9 (the tracker restarts at frame 10): the car
    // first seen at frame 12 is placed in frames 10 and 11, not in the frames before the gap.
    namespace fs = std::filesystem;
    const auto root = fs::temp_directory_path() / "cloud_analysis_tracking_hindsight_gap";
    fs::remove_all(root);
    fs::create_directories(root / "in");
    fs::create_directories(root / "out");
    const scene_schema::SequenceIndex index = write_parked_car_drive(root / "in", 2.0);
    const auto report = track_files(index, root / "in" / "sequence.json", root / "out",
                                    SequenceTrackOptions{}, [](const std::string&) {});
    CHECK(report.restarts == 1);
    const auto later = scene_schema::read_file(root / "out" / "f20.json");
    REQUIRE(later.entities.size() == 1);
    REQUIRE(later.entities.front().track_id);
    const std::int64_t id = *later.entities.front().track_id;
    for (int i = 0; i < 12; ++i) {
        CAPTURE(i);
        const auto doc =
            scene_schema::read_file(root / "out" / ("f" + std::to_string(i) + ".json"));
        CHECK((with_track(doc, id) != nullptr) == (i >= 10));
    }
    fs::remove_all(root);
}
