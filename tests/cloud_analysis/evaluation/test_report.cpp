#include <string>
#include <vector>

#include <catch2/catch.hpp>

#include "cloud_analysis/evaluation/report.hpp"

namespace {

using namespace cloud_analysis;
using scene_schema::Entity;

Entity car(const std::string& id, double x, double z) {
    Entity e;
    e.id = id;
    e.class_name = "car";
    e.x = x;
    e.y = 0.9;
    e.z = z;
    e.W = 2.0;
    e.L = 4.0;
    e.H = 1.5;
    return e;
}

bool contains(const std::string& text, const std::string& part) {
    return text.find(part) != std::string::npos;
}

}  // namespace

TEST_CASE("the disparity report has the scores in the table and in the JSON", "[report]") {
    DisparityScore s;
    s.gt_pixels = 1000;
    s.est_pixels = 900;
    s.d1_all = 0.125;
    s.d1_valid = 0.05;
    s.epe_px = 0.75;
    s.density = 0.9;
    EvaluationReport report;
    report_disparity(s, "ours.png", report);
    CHECK(report.table ==
          "disparity   D1-all 12.50 %   D1-valid 5.00 %   EPE 0.750 px   density 90.0 %   (1000 "
          "GT px)\n");
    CHECK(report.json["disparity"]["file"] == "ours.png");
    CHECK(report.json["disparity"]["gt_pixels"] == 1000);
    CHECK(report.json["disparity"]["d1_all"] == 0.125);
    CHECK(report.missed_bars.empty());
}

TEST_CASE("the entity report lists matches, misses and spurious entities, and the missed bars",
          "[report]") {
    EntityComparison c;
    c.entities_file = "est.json";
    c.reference_file = "ref.json";
    c.reference = {car("ref-1", 0.0, 10.0), car("ref-2", 5.0, 25.0)};
    c.estimate = {car("est-1", 0.0, 10.2), car("est-2", -8.0, 15.0)};
    EvalBars bars;
    bars.require_recall = 1.0;
    EvaluationReport report;
    report_entities(c, EntityEvalOptions{}, bars, report);
    const auto& j = report.json["entities"];
    CHECK(j["entities_file"] == "est.json");
    CHECK(j["reference_file"] == "ref.json");
    REQUIRE(j["matches"].size() == 1);
    CHECK(j["matches"][0]["reference"] == "ref-1");
    CHECK(j["matches"][0]["estimate"] == "est-1");
    CHECK(j["missed"] == nlohmann::json::array({"ref-2"}));
    CHECK(j["spurious"] == nlohmann::json::array({"est-2"}));
    CHECK(j["unfiltered"]["recall"] == 0.5);
    CHECK(contains(report.table, "entities est.json vs reference ref.json\n"));
    CHECK(contains(report.table, "  missed:   [\"ref-2\"]\n"));
    CHECK(contains(report.table, "  spurious: [\"est-2\"]\n"));
    CHECK(contains(report.table, ": FAIL\n"));
    REQUIRE(report.missed_bars.size() == 1);
    CHECK(contains(report.missed_bars[0], "--require-recall"));
    CHECK(report.json["bars"]["pass"] == false);
}

TEST_CASE("references too hidden to be owed are listed as not scored", "[report]") {
    EntityComparison c;
    c.reference = {car("ref-1", 0.0, 10.0), car("ref-2", 5.0, 25.0)};
    c.estimate = {car("est-1", 0.0, 10.2)};
    c.min_visible_pixels = 100;
    c.visible_pixels = {5000, 20};
    EvaluationReport report;
    report_entities(c, EntityEvalOptions{}, EvalBars{}, report);
    const auto& j = report.json["entities"];
    CHECK(j["missed"].empty());
    REQUIRE(j["not_scored"].size() == 1);
    CHECK(j["not_scored"][0]["id"] == "ref-2");
    CHECK(j["not_scored"][0]["visible_pixels"] == 20);
    // Unfiltered, the hidden car counts against the recall.
    CHECK(j["unfiltered"]["recall"] == 0.5);
    CHECK(contains(report.table, "  not scored (< 100 visible px): [{\"id\":\"ref-2\""));
    CHECK_FALSE(report.json.contains("bars"));
}

TEST_CASE("the ground plane of an entity file is reported when it has one", "[report]") {
    scene_schema::EntityDocument doc;
    EvaluationReport report;
    report_ground_plane(doc, report);
    CHECK(report.table.empty());
    CHECK_FALSE(report.json.contains("ground_plane"));
    doc.extra["ground_plane"] = {{"camera_height_m", 1.65}, {"d", 1.65}};
    report_ground_plane(doc, report);
    CHECK(report.table == "ground plane: camera 1.650 m above it\n");
    CHECK(report.json["ground_plane"]["d"] == 1.65);
}

TEST_CASE("the car report without ground-truth cars owes nothing and says the 2D rule is off",
          "[report]") {
    EvaluationReport report;
    report_cars("est.json", {car("car-1", 0.0, 10.0)}, {}, CarMatchOptions{}, GtCarOptions{},
                nullptr, report);
    CHECK(report.json["cars"]["gt_owed"] == 0);
    CHECK(report.json["cars"]["entities_in_range"] == 1);
    CHECK(report.json["cars"]["entities_matched"] == 0);
    CHECK(report.json["cars"]["fallback_max_points"].is_null());
    CHECK(contains(report.table, "  2D fallback off\n"));
    CHECK(contains(report.table, "  precision 0/1 = 0.0 %"));
}
