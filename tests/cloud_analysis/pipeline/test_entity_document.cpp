#include <catch2/catch.hpp>

#include <filesystem>

#include <scene_schema/entities.hpp>

#include "../sample_inputs.hpp"
#include "cloud_analysis/entities/class_config.hpp"
#include "cloud_analysis/pipeline/entity_document.hpp"

using namespace cloud_analysis;

namespace {

InputPaths sample_paths() { return test_samples::synthetic_paths(); }

ExtractOptions default_extract() {
    ExtractOptions extract;
    extract.classes = load_class_config(default_class_config_path());
    return extract;
}
}  // namespace

TEST_CASE("the entity document names the frame, its camera and how it was made",
          "[entity_document]") {
    const AnalyseOptions options;
    const LoadedInputs in = load_inputs(sample_paths(), options);
    const AnalyseResult r = analyse(in, options);
    const RunSettings run{options, "my-classes.json", "9.8.7", nullptr};
    const scene_schema::EntityDocument doc = entity_document(in, r, default_extract(), run);
    CHECK(doc.frame.id == "synthetic-street");
    REQUIRE(doc.frame.camera);
    CHECK(doc.frame.camera->width_px == r.camera.width_px);
    CHECK(doc.frame.camera->height_px == r.camera.height_px);
    CHECK(doc.frame.camera->fx_px == r.camera.fx_px);
    CHECK(doc.frame.camera->cx_px == r.camera.cx_px);
    CHECK(doc.frame.camera->baseline_m == r.camera.baseline_m);
    REQUIRE(doc.source);
    const nlohmann::json& source = *doc.source;
    CHECK(source.at("version") == "9.8.7");
    CHECK(source.at("extract").at("method") == "instances");
    CHECK(source.at("extract").at("class_config") == "my-classes.json");
    CHECK(source.at("extract").at("row_model") == "partition");
    CHECK(source.at("palette") == describe_run(in, options, "9.8.7").at("palette"));
    CHECK_FALSE(doc.entities.empty());
    // The text is the checked dump of the document.
    CHECK(entity_json(in, r, default_extract(), run) == scene_schema::dump_checked(doc));
}

TEST_CASE("the entity document is the same from the cloud and from per-class points",
          "[entity_document]") {
    const AnalyseOptions options;
    const LoadedInputs in = load_inputs(sample_paths(), options);
    const ExtractOptions extract = default_extract();
    const RunSettings run{options, "default", "1.0.0", nullptr};
    AnalyseOptions by_class = options;
    by_class.class_points_only = class_selection(in.palette, extract);
    const AnalyseResult from_cloud = analyse(in, options);
    const AnalyseResult from_points = analyse(in, by_class);
    REQUIRE(from_cloud.points.xyz_m.empty());
    REQUIRE_FALSE(from_points.points.xyz_m.empty());
    CHECK(entity_json(in, from_points, extract, run) == entity_json(in, from_cloud, extract, run));
}
