#include <catch2/catch.hpp>

#include "scene_viewer/sensors/drive.hpp"

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
