#include <catch2/catch.hpp>

#include <filesystem>
#include <string>
#include <vector>

#include <scene_schema/entities.hpp>

#include "cloud_analysis/entities/class_config.hpp"
#include "cloud_analysis/pipeline/batch.hpp"

using namespace cloud_analysis;

namespace {
const std::filesystem::path kStreet =
    std::filesystem::path(STEREOSCENE_SAMPLES_DIR) / "rendered" / "street";

/// A fresh empty folder under the system's temporary folder.
std::filesystem::path fresh_folder(const std::string& name) {
    const auto dir = std::filesystem::temp_directory_path() / ("cloud_analysis_" + name);
    std::filesystem::remove_all(dir);
    std::filesystem::create_directories(dir);
    return dir;
}

BatchOptions street_batch(const std::filesystem::path& out_dir) {
    BatchOptions o;
    o.kitti_root = kStreet;
    o.out_dir = out_dir;
    o.extract.classes = load_class_config(default_class_config_path());
    o.run.tool_version = "1.2.3";
    return o;
}
}  // namespace

TEST_CASE("a batch writes the frames it can and names the ones it cannot", "[batch]") {
    const auto out = fresh_folder("batch");
    BatchOptions options = street_batch(out);
    options.frames = {"000000", "999999"};
    options.cloud_formats = {"ply"};
    std::vector<std::string> failed;
    std::vector<std::size_t> done;
    BatchObserver observer;
    observer.failed = [&](const std::string& frame, const std::string&) {
        failed.push_back(frame);
    };
    observer.progress = [&](std::size_t d, std::size_t total, std::size_t, double) {
        CHECK(total == 2);
        done.push_back(d);
    };
    const BatchReport report = run_batch(options, observer);
    CHECK(report.frames == 2);
    CHECK(report.failed == 1);
    CHECK(failed == std::vector<std::string>{"999999"});
    CHECK(done == std::vector<std::size_t>{1, 2});
    REQUIRE(report.per_frame.size() == 2);
    CHECK(report.per_frame[0]["frame"] == "000000");
    CHECK_FALSE(report.per_frame[0].contains("error"));
    CHECK(report.per_frame[1].contains("error"));
    const scene_schema::EntityDocument doc = scene_schema::read_file(out / "000000.json");
    CHECK(doc.frame.id == "000000");
    REQUIRE(doc.source);
    CHECK(doc.source->at("version") == "1.2.3");
    CHECK_FALSE(doc.entities.empty());
    CHECK(std::filesystem::exists(out / "000000.ply"));
    CHECK_FALSE(std::filesystem::exists(out / "999999.json"));
    std::filesystem::remove_all(out);
}

TEST_CASE("a batch into a missing folder is refused before any frame", "[batch]") {
    BatchOptions options = street_batch(fresh_folder("batch_missing") / "absent");
    options.frames = {"000000"};
    std::size_t progress = 0;
    BatchObserver observer;
    observer.progress = [&](std::size_t, std::size_t, std::size_t, double) { ++progress; };
    CHECK_THROWS_WITH(run_batch(options, observer), Catch::Contains("no such folder"));
    CHECK(progress == 0);
}
