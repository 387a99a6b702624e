#include <catch2/catch.hpp>

#include <filesystem>

#include <scene_schema/entities.hpp>

#include "../sample_inputs.hpp"
#include "cloud_analysis/entities/class_config.hpp"
#include "cloud_analysis/entities/entity_document.hpp"

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
    const RunSettings run{options, "my-classes.json", "9.8.7"};
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
    const RunSettings run{options, "default", "1.0.0"};
    AnalyseOptions by_class = options;
    by_class.class_points_only = class_selection(in.palette, extract);
    const AnalyseResult from_cloud = analyse(in, options);
    const AnalyseResult from_points = analyse(in, by_class);
    REQUIRE(from_cloud.points.xyz_m.empty());
    REQUIRE_FALSE(from_points.points.xyz_m.empty());
    CHECK(entity_json(in, from_points, extract, run) == entity_json(in, from_cloud, extract, run));
}

TEST_CASE("things seen over too little of their smallest face are dropped, ids renumbered",
          "[entity_document]") {
    const ClassConfig classes = load_class_config(default_class_config_path());
    const ClassSettings car = classes.find("car");
    REQUIRE(car.has_prior());
    const double face_m2 = car.prior_W_m * car.prior_H_m;
    // At 20 m with f = 500 px each point covers (20 / 500)^2 = 0.0016 m^2.
    const auto points_for = [](double m2) { return static_cast<std::int64_t>(m2 / 0.0016); };
    std::vector<scene_schema::Entity> entities(4);
    entities[0].class_name = "car";  // a roof fragment: 5 % of the face
    entities[0].point_count = points_for(0.05 * face_m2);
    entities[1].class_name = "car";  // a car seen over a fifth of its face
    entities[1].point_count = points_for(0.2 * face_m2);
    entities[2].class_name = "road";  // stuff keeps any support
    entities[2].point_count = 3;
    entities[3].class_name = "car";
    entities[3].point_count = points_for(face_m2);
    for (std::size_t i = 0; i < entities.size(); ++i) {
        entities[i].z = 20.0;
        entities[i].id = entities[i].class_name + "-" + std::to_string(i + 1);
    }
    drop_faint_things(entities, classes, 500.0, 500.0, 0.15);
    REQUIRE(entities.size() == 3);
    CHECK(entities[0].id == "car-1");
    CHECK(entities[0].point_count == points_for(0.2 * face_m2));
    CHECK(entities[1].id == "road-1");
    CHECK(entities[2].id == "car-2");
    drop_faint_things(entities, classes, 500.0, 500.0, 0.0);  // off
    CHECK(entities.size() == 3);
}
