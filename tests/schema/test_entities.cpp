#include <catch2/catch.hpp>

#include <array>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <limits>
#include <sstream>

#include <unistd.h>

#include "scene_schema/entities.hpp"
#include "scene_schema/json_text.hpp"

namespace fs = std::filesystem;
using nlohmann::json;
using scene_schema::EntityDocument;
using scene_schema::SchemaError;

namespace {

std::string slurp(const fs::path& path) {
    std::ifstream in(path, std::ios::binary);
    std::ostringstream out;
    out << in.rdbuf();
    return out.str();
}

/// Entity files under root: every .json except scene-render sensors' visibility/ records,
/// sequence indexes (sequence.json, tests/schema/test_sequence.cpp) and 2D labels (labels-2d/).
std::vector<fs::path> json_files_under(const fs::path& root) {
    std::vector<fs::path> files;
    for (const auto& entry : fs::recursive_directory_iterator(root)) {
        if (entry.is_regular_file() && entry.path().extension() == ".json" &&
            entry.path().parent_path().filename() != "visibility" &&
            entry.path().parent_path().filename() != "labels-2d" &&
            entry.path().filename() != "sequence.json") {
            files.push_back(entry.path());
        }
    }
    std::sort(files.begin(), files.end());
    return files;
}

/// A scratch folder unique to the running test, removed at the end.
struct ScratchDir {
    fs::path path;
    ScratchDir() {
        path =
            fs::temp_directory_path() / ("stereoscene-schema-" + std::to_string(::getpid()) + "-" +
                                         std::to_string(reinterpret_cast<std::uintptr_t>(this)));
        fs::create_directories(path);
    }
    ~ScratchDir() { fs::remove_all(path); }
};

EntityDocument small_document() {
    EntityDocument doc;
    doc.frame.id = "unit";
    scene_schema::Entity car;
    car.id = "car-1";
    car.class_name = "car";
    car.class_id = 26;
    car.x = 2.0;
    car.y = 0.9;
    car.z = 15.0;
    car.theta = -1.5;
    car.W = 1.8;
    car.H = 1.5;
    car.L = 4.2;
    car.point_count = 1000;
    car.confidence = 0.75;
    car.method = "instances";
    doc.entities.push_back(car);
    return doc;
}

}  // namespace

TEST_CASE("every JSON file under samples validates and survives a round trip unchanged",
          "[schema]") {
    const auto files = json_files_under(STEREOSCENE_SAMPLES_DIR);
    REQUIRE_FALSE(files.empty());
    for (const auto& path : files) {
        INFO(path.string());
        const json original = json::parse(slurp(path));
        CHECK(scene_schema::validate(original).empty());
        const EntityDocument doc = scene_schema::read_file(path);
        const json round_trip = scene_schema::to_json(doc);
        CHECK(round_trip == original);
        // The canonical text is a fixed point of read -> write.
        const std::string text = scene_schema::dump(doc);
        CHECK(scene_schema::dump(scene_schema::parse(text)) == text);
    }
}

TEST_CASE("good test documents validate, unknown members are kept verbatim", "[schema]") {
    for (const auto& path :
         json_files_under(fs::path(STEREOSCENE_TEST_DATA_DIR) / "schema" / "good")) {
        INFO(path.string());
        const json original = json::parse(slurp(path));
        CHECK(scene_schema::to_json(scene_schema::read_file(path)) == original);
    }
    const auto doc = scene_schema::read_file(fs::path(STEREOSCENE_TEST_DATA_DIR) / "schema" /
                                             "good" / "extra_fields.json");
    CHECK(doc.extra.at("x_note").at("kept") == json::array({1, 2, 3}));
    CHECK(doc.frame.extra.at("x_sensor") == "left");
    CHECK(doc.entities.at(0).extra.at("x_track_id") == 17);
    REQUIRE(doc.frame.camera.has_value());
    CHECK(doc.frame.camera->fx_px == Approx(721.5377));
    CHECK(doc.schema_version == "1.3.0");
}

TEST_CASE("each broken document fails with the expected JSON pointer", "[schema]") {
    const fs::path data = fs::path(STEREOSCENE_TEST_DATA_DIR) / "schema";
    const json expected = json::parse(slurp(data / "broken_expected.json"));
    const auto files = json_files_under(data / "broken");
    REQUIRE(files.size() == expected.size());
    for (const auto& path : files) {
        const std::string name = path.filename().string();
        INFO(name);
        REQUIRE(expected.contains(name));
        const std::string pointer = expected.at(name).at("pointer");
        try {
            scene_schema::parse(slurp(path));
            FAIL("parsed a broken document");
        } catch (const SchemaError& e) {
            CHECK(e.pointer() == pointer);
            CHECK(std::string(e.what()) == pointer + ": " + e.rule());
            CHECK(std::string(e.what()).find('\n') == std::string::npos);
        }
    }
}

TEST_CASE("validation messages name the pointer and the rule", "[schema]") {
    json j = scene_schema::to_json(small_document());
    j["entities"][0]["W"] = -1.0;
    j["entities"][0].erase("confidence");
    const auto issues = scene_schema::validate(j);
    REQUIRE(issues.size() == 2);
    CHECK(issues[0].message() == "/entities/0/W: must be > 0");
    CHECK(issues[1].message() == "/entities/0/confidence: is required");

    json dup = scene_schema::to_json(small_document());
    dup["entities"].push_back(dup["entities"][0]);
    const auto dup_issues = scene_schema::validate(dup);
    REQUIRE(dup_issues.size() == 1);
    CHECK(dup_issues[0].message() ==
          "/entities/1/id: duplicate id \"car-1\" (first at /entities/0)");

    json major = scene_schema::to_json(small_document());
    major["schema_version"] = "2.1.0";
    REQUIRE(scene_schema::validate(major).size() == 1);
    CHECK(scene_schema::validate(major)[0].message() ==
          "/schema_version: unsupported major version 2 (this reader reads 1.x.y)");
}

TEST_CASE("camera intrinsics are validated with their pointer", "[schema]") {
    json j = scene_schema::to_json(small_document());
    j["frame"]["camera"] = {{"width", 0}, {"height", 1}, {"fx", 1},
                            {"fy", 1},    {"cx", 0},     {"cy", 0}};
    CHECK(scene_schema::validate(j).at(0).message() == "/frame/camera/width: must be >= 1");
}

TEST_CASE("writing is atomic: the file appears whole or not at all", "[schema]") {
    ScratchDir dir;
    const fs::path target = dir.path / "out.json";
    scene_schema::write_file(small_document(), target);
    REQUIRE(fs::exists(target));
    const std::string first = slurp(target);
    CHECK(scene_schema::dump(scene_schema::read_file(target)) == first);

    // An invalid document is refused before anything is written and the old file stays intact.
    EntityDocument bad = small_document();
    bad.entities[0].L = 0.0;
    CHECK_THROWS_AS(scene_schema::write_file(bad, target), SchemaError);
    CHECK(slurp(target) == first);

    // A non-finite value (which JSON cannot hold) is refused too.
    EntityDocument nan = small_document();
    nan.entities[0].x = std::numeric_limits<double>::quiet_NaN();
    CHECK_THROWS_AS(scene_schema::write_file(nan, dir.path / "nan.json"), SchemaError);
    CHECK_FALSE(fs::exists(dir.path / "nan.json"));

    // A folder that does not exist: a clear error naming the file, no stray temp files.
    const fs::path missing = dir.path / "no-such-dir" / "out.json";
    try {
        scene_schema::write_file(small_document(), missing);
        FAIL("wrote into a missing folder");
    } catch (const scene_schema::FileError& e) {
        CHECK(std::string(e.what()).find(missing.string()) != std::string::npos);
    }
    std::size_t count = 0;
    for ([[maybe_unused]] const auto& entry : fs::directory_iterator(dir.path)) ++count;
    CHECK(count == 1);  // only out.json
}

TEST_CASE("dump_checked gives dump's text and refuses what check refuses", "[schema]") {
    CHECK(scene_schema::dump_checked(small_document()) == scene_schema::dump(small_document()));
    EntityDocument bad = small_document();
    bad.entities[0].L = 0.0;
    CHECK_THROWS_AS(scene_schema::check(bad), SchemaError);
    CHECK_THROWS_AS(scene_schema::dump_checked(bad), SchemaError);
    bad = small_document();
    bad.entities[0].x = std::numeric_limits<double>::infinity();
    CHECK_THROWS_AS(scene_schema::dump_checked(bad), SchemaError);
}

TEST_CASE("read errors name the file", "[schema]") {
    const fs::path truncated =
        fs::path(STEREOSCENE_TEST_DATA_DIR) / "schema" / "broken" / "truncated.json";
    try {
        scene_schema::read_file(truncated);
        FAIL("read a truncated file");
    } catch (const scene_schema::FileError& e) {
        const std::string what = e.what();
        CHECK(what.rfind(truncated.string() + ": /entities/0: not valid JSON: parse error at line",
                         0) == 0);
    }
    CHECK_THROWS_AS(scene_schema::read_file("/nonexistent/entities.json"), scene_schema::FileError);
}

TEST_CASE("JSON text errors name the pointer where the text breaks, in one line", "[schema]") {
    using scene_schema::parse_json;
    auto pointer_of = [](const std::string& text) {
        try {
            parse_json(text);
        } catch (const SchemaError& e) {
            CHECK(std::string(e.what()).find("json.exception") == std::string::npos);
            CHECK(std::string(e.what()).find('\n') == std::string::npos);
            return e.pointer();
        }
        FAIL("parsed: " << text);
        return std::string();
    };
    CHECK(pointer_of(R"({"a": {"b": [1, 2, 1e400]}})") == "/a/b/2");
    CHECK(pointer_of(R"({"a": [{"x": 1}, {"y/z~": NaN}]})") == "/a/1/y~1z~0");
    CHECK(pointer_of(R"([[1], [2, Infinity]])") == "/1/1");
    CHECK(pointer_of(R"({"a": )") == "/a");
    CHECK(pointer_of("") == "");
    // Long member names are cut to 40 characters.
    CHECK(pointer_of("{\"" + std::string(100, 'k') + "\": NaN}") ==
          "/" + std::string(40, 'k') + "...");
    try {
        parse_json(R"({"x": 1e400})");
    } catch (const SchemaError& e) {
        CHECK(e.rule() == "not valid JSON: number overflow parsing '1e400'");
    }
}

TEST_CASE("JSON nested past the depth limit is refused before any walk of it", "[schema]") {
    const std::size_t depth = scene_schema::kMaxJsonDepth;
    // At the limit: read. One level more: refused at the innermost container's pointer.
    const std::string at_limit = std::string(depth, '[') + std::string(depth, ']');
    CHECK(scene_schema::parse_json(at_limit).is_array());
    const std::string beyond = std::string(depth + 1, '[') + std::string(depth + 1, ']');
    try {
        scene_schema::parse_json(beyond);
        FAIL("read JSON nested deeper than the limit");
    } catch (const SchemaError& e) {
        CHECK(e.rule() == "nested deeper than " + std::to_string(depth) + " levels");
        // The pointer is cut to its first six and its last segment (one short line).
        CHECK(e.pointer() == "/0/0/0/0/0/0/.../0");
    }
    // A million levels in an entity file's free-form member: an error, not a stack overflow.
    const std::string huge = std::string(1000000, '[') + std::string(1000000, ']');
    const std::string text = R"({"schema_version": "1.0.0", "frame": {"id": "f",)"
                             R"( "convention": "kitti_camera"}, "entities": [], "x": )" +
                             huge + "}";
    CHECK_THROWS_AS(scene_schema::parse(text), SchemaError);
}

TEST_CASE("a tool file's format and version header is checked in one line", "[schema]") {
    using scene_schema::format_header_problem;
    CHECK_FALSE(format_header_problem(json{{"format", "x-tool"}, {"version", 2}}, "x-tool", 2));
    CHECK(format_header_problem(json::array(), "x-tool", 2) == "(document): must be an object");
    CHECK(format_header_problem(json{{"version", 2}}, "x-tool", 2) ==
          "/format: must be \"x-tool\"");
    CHECK(format_header_problem(json{{"format", 7}, {"version", 2}}, "x-tool", 2) ==
          "/format: must be \"x-tool\"");
    CHECK(format_header_problem(json{{"format", "x-tool"}}, "x-tool", 2) == "/version: must be 2");
    CHECK(format_header_problem(json{{"format", "x-tool"}, {"version", "2"}}, "x-tool", 2) ==
          "/version: must be 2");
}

TEST_CASE("a leading UTF-8 byte order mark is skipped (RFC 8259 8.1)", "[schema]") {
    const std::string text = "\xEF\xBB\xBF" + scene_schema::dump(small_document());
    CHECK(scene_schema::parse(text).entities.size() == small_document().entities.size());
}

TEST_CASE("numbers beyond the schema's bounds are refused at their pointer", "[schema]") {
    const json good = scene_schema::to_json(small_document());
    const std::vector<std::pair<std::string, double>> cases = {
        {"/entities/0/x", 1e30},        {"/entities/0/z", -2e5},
        {"/entities/0/class_id", 1e30}, {"/entities/0/point_count", 1e17},
        {"/entities/0/L", 2e4},         {"/entities/0/theta", 1e4},
        {"/frame/camera/width", 2e6},   {"/frame/camera/fx", 1e300},
    };
    for (const auto& [pointer, value] : cases) {
        INFO(pointer);
        json j = good;
        if (!j["frame"].contains("camera")) {
            j["frame"]["camera"] = {{"width", 640}, {"height", 480}, {"fx", 500.0},
                                    {"fy", 500.0},  {"cx", 320.0},   {"cy", 240.0}};
        }
        REQUIRE(scene_schema::validate(j).empty());
        j[json::json_pointer(pointer)] = value;
        const auto issues = scene_schema::validate(j);
        REQUIRE(issues.size() == 1);
        CHECK(issues[0].pointer == pointer);
        CHECK(issues[0].rule.rfind("must be between", 0) == 0);
    }
}

TEST_CASE("read_file reads standard input for the path -", "[schema]") {
    std::istringstream input(scene_schema::dump(small_document()));
    std::streambuf* saved = std::cin.rdbuf(input.rdbuf());
    const EntityDocument doc = scene_schema::read_file("-");
    std::cin.rdbuf(saved);
    CHECK(scene_schema::dump(doc) == scene_schema::dump(small_document()));

    std::istringstream broken("{\"schema_version\": 1}");
    saved = std::cin.rdbuf(broken.rdbuf());
    try {
        scene_schema::read_file("-");
        std::cin.rdbuf(saved);
        FAIL("read a broken document from standard input");
    } catch (const scene_schema::FileError& e) {
        std::cin.rdbuf(saved);
        CHECK(std::string(e.what()) == "-: /schema_version: must be a string");
    }
}

TEST_CASE("a frame with a pose gives every entity its box in the world, derived on write",
          "[schema]") {
    EntityDocument doc = small_document();
    CHECK_FALSE(scene_schema::to_json(doc).at("entities").at(0).contains("world"));
    // The camera turned 30 degrees about +y, 3 m along world x and 1 m up (y is down).
    const double a = 30.0 * 3.14159265358979323846 / 180.0;
    doc.frame.pose = std::array<double, 12>{std::cos(a),  0.0, std::sin(a), 3.0,   //
                                            0.0,          1.0, 0.0,         -1.0,  //
                                            -std::sin(a), 0.0, std::cos(a), 0.0};
    const json world = scene_schema::to_json(doc).at("entities").at(0).at("world");
    const auto& car = doc.entities.at(0);
    CHECK(world.at("x").get<double>() == Approx(std::cos(a) * car.x + std::sin(a) * car.z + 3.0));
    CHECK(world.at("y").get<double>() == Approx(car.y - 1.0));
    CHECK(world.at("z").get<double>() == Approx(-std::sin(a) * car.x + std::cos(a) * car.z));
    // A yaw about +y adds to the heading.
    CHECK(world.at("theta").get<double>() == Approx(car.theta + a));
    // Read back, the box moved by a tracker is written at its new place: never a stale copy.
    EntityDocument read = scene_schema::parse(scene_schema::dump(doc));
    read.entities.at(0).x += 1.0;
    const json moved = scene_schema::to_json(read).at("entities").at(0).at("world");
    CHECK(moved.at("x").get<double>() == Approx(world.at("x").get<double>() + std::cos(a)));
    CHECK_FALSE(read.entities.at(0).extra.contains("world"));
    // Without the pose there is no world to place it in.
    read.frame.pose.reset();
    CHECK_FALSE(scene_schema::to_json(read).at("entities").at(0).contains("world"));
}
