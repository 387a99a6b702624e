#include <cmath>

#include <catch2/catch.hpp>

#include "scene_viewer/sensors/drive.hpp"
#include "scene_viewer/views/trails.hpp"
#include "stereoscene/support/angles.hpp"

using namespace scene_viewer;

TEST_CASE("a drive moves entities by their velocity and names each object the same way",
          "[sensors][drive]") {
    scene_schema::EntityDocument scene;
    scene.frame.id = "drive";
    scene_schema::Entity road;
    road.id = "road-1";
    road.class_name = "road";
    road.class_id = 7;
    scene_schema::Entity parked = road;
    parked.id = "car-1";
    parked.class_name = "car";
    parked.class_id = 26;
    parked.x = 4.0;
    parked.z = 10.0;
    scene_schema::Entity moving = parked;
    moving.id = "car-2";
    moving.velocity = scene_schema::Velocity{2.0, -5.0};
    moving.track_id = 40;
    scene.entities = {road, parked, moving};

    const auto at = scene_at(scene, 0.5, drive_frame_name(5));
    CHECK(at.frame.id == "0000000005");
    CHECK(*at.frame.timestamp_s == 0.5);
    CHECK_FALSE(at.entities[0].track_id);  // stuff has no track
    CHECK(*at.entities[1].track_id == 1);  // its position in the file
    CHECK(at.entities[1].x == 4.0);
    CHECK(at.entities[1].velocity->vz_mps == 0.0);  // parked: still, and said so
    CHECK(*at.entities[2].track_id == 40);          // the file's own id is kept
    CHECK(at.entities[2].x == Approx(5.0));
    CHECK(at.entities[2].z == Approx(7.5));
    scene_schema::check(at);
}

TEST_CASE("a drive's index lists every frame at the frame rate", "[sensors][drive]") {
    DriveOptions options;
    options.frames = 3;
    options.fps = 4.0;
    const auto index = drive_index("d", options);
    REQUIRE(index.frames.size() == 3);
    CHECK(index.frames[2].file == "0000000002.json");
    CHECK(*index.frames[2].timestamp_s == 0.5);
    CHECK(scene_schema::validate_sequence(scene_schema::to_json(index)).empty());
    options.fps = 0.0;
    CHECK_THROWS_WITH(options.validate(), "--fps must be in (0, 1000]");
    options = DriveOptions{};
    options.frames = 0;
    CHECK_THROWS_WITH(options.validate(), "--frames must be between 1 and 100000");
}

TEST_CASE("a still camera's drive has no poses", "[sensors][drive]") {
    scene_schema::EntityDocument scene;
    CHECK_FALSE(EgoMotion{}.moving());
    CHECK_FALSE(scene_at(scene, 1.0, "f", EgoMotion{}).frame.pose);
}

TEST_CASE("the ego camera drives straight along +z, or a quarter circle to the right",
          "[sensors][drive]") {
    const EgoMotion straight{8.0, 0.0};
    const auto p = straight.pose_at(2.5);
    CHECK(p[0] == 1.0);
    CHECK(p[3] == Approx(0.0).margin(1e-12));
    CHECK(p[11] == Approx(20.0));
    // 10 deg/s for 9 s turns 90 degrees on a circle of radius v / w.
    const EgoMotion curve{10.0, 10.0};
    const double r = 10.0 / (10.0 * stereoscene::support::kPi / 180.0);
    const auto q = curve.pose_at(9.0);
    CHECK(q[0] == Approx(0.0).margin(1e-12));  // cos 90
    CHECK(q[2] == Approx(1.0));                // the camera's z now points along +x
    CHECK(q[8] == Approx(-1.0));
    CHECK(q[3] == Approx(r));   // x = r (1 - cos 90)
    CHECK(q[11] == Approx(r));  // z = r sin 90
    CHECK(q[7] == 0.0);         // on the road plane
}

TEST_CASE("with a moving camera the scene is the world, seen from where the camera is",
          "[sensors][drive]") {
    scene_schema::EntityDocument scene;
    scene_schema::Entity parked;
    parked.id = "car-1";
    parked.class_name = "car";
    parked.class_id = 26;
    parked.x = 10.0;  // 10 m right of the start, 10 m ahead
    parked.y = 0.9;
    parked.z = 10.0;
    parked.theta = -stereoscene::support::kHalfPi;  // along +z
    scene_schema::Entity moving = parked;
    moving.id = "car-2";
    moving.x = 0.0;
    moving.z = 0.0;
    moving.velocity = scene_schema::Velocity{10.0, 0.0};  // crossing to the right
    scene.entities = {parked, moving};

    // Straight at 5 m/s for 1 s: the parked car is 5 m nearer, nothing else changes.
    const auto ahead = scene_at(scene, 1.0, "f", EgoMotion{5.0, 0.0});
    REQUIRE(ahead.frame.pose);
    CHECK(ahead.entities[0].z == Approx(5.0));
    CHECK(ahead.entities[0].x == Approx(10.0));
    CHECK(ahead.entities[0].y == 0.9);

    // After a quarter circle to the right the camera looks along the world's +x: a car that
    // heads along the world's +z heads to the camera's left, its velocity turns with it.
    const EgoMotion curve{10.0, 10.0};
    const auto turned = scene_at(scene, 9.0, "f", curve);
    const auto& pose = *turned.frame.pose;
    // The parked car in the camera: R^T (X - t).
    const double dx = 10.0 - pose[3], dz = 10.0 - pose[11];
    CHECK(turned.entities[0].x == Approx(pose[0] * dx + pose[8] * dz).margin(1e-9));
    CHECK(turned.entities[0].z == Approx(pose[2] * dx + pose[10] * dz).margin(1e-9));
    CHECK(std::abs(std::remainder(turned.entities[0].theta - stereoscene::support::kPi,
                                  2 * stereoscene::support::kPi)) < 1e-9);
    CHECK(turned.entities[1].velocity->vx_mps == Approx(0.0).margin(1e-9));
    CHECK(turned.entities[1].velocity->vz_mps == Approx(10.0));
    scene_schema::check(turned);
}

TEST_CASE("poses are written as KITTI odometry text, one 3x4 matrix a line", "[sensors][drive]") {
    const std::string text = scene_schema::format_kitti_poses(
        {EgoMotion{}.pose_at(0.0), EgoMotion{2.0, 0.0}.pose_at(1.0)});
    CHECK(text ==
          "1.000000000e+00 0.000000000e+00 0.000000000e+00 0.000000000e+00 0.000000000e+00 "
          "1.000000000e+00 0.000000000e+00 0.000000000e+00 0.000000000e+00 0.000000000e+00 "
          "1.000000000e+00 0.000000000e+00\n"
          "1.000000000e+00 0.000000000e+00 0.000000000e+00 0.000000000e+00 0.000000000e+00 "
          "1.000000000e+00 0.000000000e+00 0.000000000e+00 0.000000000e+00 0.000000000e+00 "
          "1.000000000e+00 2.000000000e+00\n");
}

TEST_CASE("with poses, trails stay where things were in the world and the camera's path is one",
          "[trails][drive]") {
    // A parked car 10 m ahead of the start, seen from a camera driving 2 m a frame.
    scene_schema::EntityDocument world;
    scene_schema::Entity parked;
    parked.id = "car-1";
    parked.class_name = "car";
    parked.class_id = 26;
    parked.x = 3.0;
    parked.y = 0.9;
    parked.z = 10.0;
    parked.H = 1.5;
    parked.W = 1.8;
    parked.L = 4.2;
    world.entities = {parked};
    TrailHistory trails(10);
    const EgoMotion ego{20.0, 0.0};
    for (int i = 0; i < 3; ++i) trails.remember(scene_at(world, 0.1 * i, "f", ego));
    const auto now = scene_at(world, 0.3, "f", ego);
    const auto drawn = trails.with_trails(now);
    int car_marks = 0, ego_marks = 0;
    for (const auto& e : drawn.entities) {
        if (e.class_name != "trail") continue;
        CHECK(e.y + e.H / 2 == Approx(1.65));  // on the ground
        if (e.id.rfind("trail-ego-", 0) == 0) {
            ++ego_marks;
            CHECK(e.class_id == kEgoClassId);
            CHECK(e.x == Approx(0.0).margin(1e-9));
            CHECK(e.z < 0.0);  // behind the camera now
        } else {
            ++car_marks;
            // Every mark of the parked car lies under it now: 10 - 6 = 4 m ahead.
            CHECK(e.x == Approx(3.0));
            CHECK(e.z == Approx(4.0));
        }
    }
    CHECK(car_marks == 3);
    CHECK(ego_marks == 3);
}
