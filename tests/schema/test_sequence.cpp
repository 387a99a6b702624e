#include <catch2/catch.hpp>

#include <filesystem>
#include <fstream>
#include <sstream>

#include <unistd.h>

#include "scene_schema/entities.hpp"
#include "scene_schema/sequence.hpp"

namespace fs = std::filesystem;
using nlohmann::json;
using scene_schema::SchemaError;

namespace {

json tracked_entity() {
    return json::parse(R"({"id": "car-1", "class": "car", "class_id": 26, "x": 1.5, "y": 0.9,
        "z": 12.0, "theta": -1.57, "W": 1.8, "H": 1.5, "L": 4.2, "point_count": 10,
        "confidence": 0.9, "track_id": 7, "velocity": {"vx": 0.5, "vz": -3.25}})");
}

json document_with(const json& entity, const char* version = "1.1.0") {
    return {{"schema_version", version},
            {"frame", {{"id", "0000000001"}, {"convention", "kitti_camera"}, {"timestamp", 0.1}}},
            {"entities", json::array({entity})}};
}

json three_frames() {
    return json::parse(R"({"schema_version": "1.1.0", "id": "drive", "fps": 10,
        "frames": [{"index": 0, "file": "0000000000.json", "timestamp": 0.0},
                   {"index": 1, "file": "0000000001.json", "timestamp": 0.1},
                   {"index": 3, "file": "0000000003.json", "timestamp": 0.3}]})");
}

std::string first_issue(const json& index) {
    const auto issues = scene_schema::validate_sequence(index);
    return issues.empty() ? "" : issues.front().message();
}

}  // namespace

TEST_CASE("schema 1.1 members are read into their fields and written back", "[schema]") {
    const auto doc = scene_schema::from_json(document_with(tracked_entity()));
    REQUIRE(doc.frame.timestamp_s.has_value());
    CHECK(*doc.frame.timestamp_s == Approx(0.1));
    const auto& e = doc.entities.at(0);
    REQUIRE(e.track_id.has_value());
    CHECK(*e.track_id == 7);
    REQUIRE(e.velocity.has_value());
    CHECK(e.velocity->vx_mps == 0.5);
    CHECK(e.velocity->vz_mps == -3.25);
    CHECK(e.extra.empty());
    CHECK(scene_schema::to_json(doc) == document_with(tracked_entity()));
}

TEST_CASE("a 1.0 file without the 1.1 members still reads and keeps its version", "[schema]") {
    json entity = tracked_entity();
    entity.erase("track_id");
    entity.erase("velocity");
    json old = document_with(entity, "1.0.0");
    old["frame"].erase("timestamp");
    const auto doc = scene_schema::from_json(old);
    CHECK_FALSE(doc.entities.at(0).track_id);
    CHECK_FALSE(doc.entities.at(0).velocity);
    CHECK_FALSE(doc.frame.timestamp_s);
    CHECK(scene_schema::to_json(doc) == old);
    const scene_schema::EntityDocument fresh;
    CHECK(fresh.schema_version == scene_schema::kSchemaVersion);
}

TEST_CASE("the 1.1 members are validated at their pointers", "[schema]") {
    json e = tracked_entity();
    e["track_id"] = 1.5;
    CHECK(scene_schema::validate(document_with(e)).at(0).message() ==
          "/entities/0/track_id: must be an integer");
    e = tracked_entity();
    e["velocity"] = {{"vx", 1.0}};
    CHECK(scene_schema::validate(document_with(e)).at(0).message() ==
          "/entities/0/velocity/vz: is required");
    e = tracked_entity();
    e["velocity"] = 3.0;
    CHECK(scene_schema::validate(document_with(e)).at(0).message() ==
          "/entities/0/velocity: must be an object");
    json d = document_with(tracked_entity());
    d["frame"]["timestamp"] = "0.1";
    CHECK(scene_schema::validate(d).at(0).message() == "/frame/timestamp: must be a number");
}

TEST_CASE("a non-finite velocity is refused before writing", "[schema]") {
    auto doc = scene_schema::from_json(document_with(tracked_entity()));
    doc.entities[0].velocity->vz_mps = std::nan("");
    CHECK_THROWS_AS(scene_schema::check(doc), SchemaError);
}

TEST_CASE("a sequence index validates, round-trips and resolves its files", "[schema][sequence]") {
    const json j = three_frames();
    CHECK(scene_schema::validate_sequence(j).empty());
    CHECK(scene_schema::is_sequence_index(j));
    CHECK_FALSE(scene_schema::is_sequence_index(document_with(tracked_entity())));
    const auto index = scene_schema::sequence_from_json(j);
    REQUIRE(index.frames.size() == 3);
    CHECK(index.frames[2].index == 3);
    CHECK(*index.fps == 10.0);
    CHECK(scene_schema::to_json(index) == j);
    CHECK(scene_schema::frame_file("/d/out/sequence.json", index.frames[1]) ==
          fs::path("/d/out/0000000001.json"));
}

TEST_CASE("a sequence index refuses disorder and paths outside its folder", "[schema][sequence]") {
    json j = three_frames();
    j["frames"][2]["index"] = 1;
    CHECK(first_issue(j) == "/frames/2/index: must be greater than the previous frame's index");
    j = three_frames();
    j["frames"][1]["timestamp"] = -0.5;
    CHECK(first_issue(j) == "/frames/1/timestamp: must be between 0 and 100000000000");
    j = three_frames();
    j["frames"][2]["timestamp"] = 0.05;
    CHECK(first_issue(j) ==
          "/frames/2/timestamp: must not be earlier than the previous frame's timestamp");
    j = three_frames();
    j["frames"][0]["file"] = "../elsewhere.json";
    CHECK(first_issue(j) == "/frames/0/file: must be a relative path inside the index's folder");
    j = three_frames();
    j["frames"][0].erase("file");
    CHECK(first_issue(j) == "/frames/0/file: is required");
    j = three_frames();
    j["fps"] = 0;
    CHECK(first_issue(j) == "/fps: must be > 0");
    j = three_frames();
    j["schema_version"] = "2.0.0";
    CHECK(first_issue(j) ==
          "/schema_version: unsupported major version 2 (this reader reads 1.x.y)");
}

TEST_CASE("a sequence index file is written atomically and read back", "[schema][sequence]") {
    const fs::path dir =
        fs::temp_directory_path() / ("stereoscene-sequence-" + std::to_string(::getpid()));
    fs::create_directories(dir);
    const auto index = scene_schema::sequence_from_json(three_frames());
    scene_schema::write_sequence_file(index, dir / "sequence.json");
    CHECK(scene_schema::to_json(scene_schema::read_sequence_file(dir / "sequence.json")) ==
          three_frames());
    std::ofstream(dir / "bad.json") << R"({"schema_version": "1.1.0", "id": "d", "frames": 3})";
    try {
        scene_schema::read_sequence_file(dir / "bad.json");
        FAIL("read a broken index");
    } catch (const scene_schema::FileError& e) {
        CHECK(std::string(e.what()) == (dir / "bad.json").string() + ": /frames: must be an array");
    }
    auto broken = index;
    broken.frames[1].index = 0;
    CHECK_THROWS_AS(scene_schema::write_sequence_file(broken, dir / "broken.json"), SchemaError);
    CHECK_FALSE(fs::exists(dir / "broken.json"));
    fs::remove_all(dir);
}
