#include <catch2/catch.hpp>

#include <nlohmann/json.hpp>

#include "cloud_analysis/pipeline/batch_report.hpp"

using namespace cloud_analysis;
using nlohmann::json;

namespace {

/// A shard report as `batch --shard index/count --report` writes it (the fields merged).
json shard_report(int index, int count, std::size_t done, std::size_t skipped, std::size_t failed,
                  double started, double ended) {
    json failures = json::array();
    for (std::size_t i = 0; i < failed; ++i) {
        failures.push_back({{"frame", "f" + std::to_string(index) + "_" + std::to_string(i)},
                            {"error", "cannot read image"}});
    }
    return {{"shard", {{"index", index}, {"count", count}}},
            {"frames", done + skipped + failed},
            {"done", done},
            {"skipped", skipped},
            {"failed", failed},
            {"failures", failures},
            {"started_at", started},
            {"ended_at", ended},
            {"seconds", ended - started},
            {"fps", static_cast<double>(done) / (ended - started)},
            {"cpu_seconds", 0.1 * static_cast<double>(done)},
            {"peak_rss_mb", 100.0 + index},
            {"preset", "fast"},
            {"per_frame", json::array()}};
}

}  // namespace

TEST_CASE("shard reports merge: counts add, the run spans first start to last end", "[report]") {
    const json merged = merge_batch_reports(
        {shard_report(1, 3, 10, 2, 1, 1000.0, 1010.0), shard_report(0, 3, 12, 0, 0, 1002.0, 1008.0),
         shard_report(2, 3, 8, 4, 0, 1001.0, 1005.0)},
        3);
    CHECK(merged["shards"] == 3);
    CHECK(merged["shards_reported"] == 3);
    CHECK(merged["missing_shards"].empty());
    CHECK(merged["frames"] == 37);
    CHECK(merged["done"] == 30);
    CHECK(merged["skipped"] == 6);
    CHECK(merged["failed"] == 1);
    REQUIRE(merged["failures"].size() == 1);
    CHECK(merged["failures"][0]["frame"] == "f1_0");
    CHECK(merged["failures"][0]["error"] == "cannot read image");
    CHECK(merged["wall_seconds"].get<double>() == Approx(10.0));
    CHECK(merged["fps"].get<double>() == Approx(3.0));
    CHECK(merged["task_seconds"].get<double>() == Approx(20.0));
    CHECK(merged["fps_per_task"].get<double>() == Approx(1.5));
    CHECK(merged["cpu_seconds"].get<double>() == Approx(3.0));
    CHECK(merged["cpu_ms_per_frame"].get<double>() == Approx(100.0));
    CHECK(merged["peak_rss_mb"].get<double>() == Approx(102.0));
    CHECK(merged["preset"] == "fast");
    REQUIRE(merged["per_shard"].size() == 3);
    CHECK(merged["per_shard"][0]["index"] == 0);
    CHECK(merged["per_shard"][2]["skipped"] == 4);
}

TEST_CASE("frames that warned add up across shards and older reports count none", "[report]") {
    json a = shard_report(0, 2, 5, 0, 0, 0.0, 1.0);
    a["frames_with_warnings"] = 2;
    const json b = shard_report(1, 2, 5, 0, 0, 0.0, 1.0);  // written before the field existed
    CHECK(merge_batch_reports({a, b}, 2)["frames_with_warnings"] == 2);
    json c = b;
    c["frames_with_warnings"] = 3;
    CHECK(merge_batch_reports({a, c}, 2)["frames_with_warnings"] == 5);
}

TEST_CASE("a missing shard is listed and a duplicate or foreign report is refused", "[report]") {
    const json merged = merge_batch_reports(
        {shard_report(0, 4, 5, 0, 0, 0.0, 1.0), shard_report(3, 4, 5, 0, 0, 0.0, 2.0)}, 4);
    CHECK(merged["missing_shards"] == json::array({1, 2}));
    CHECK(merged["shards_reported"] == 2);
    CHECK(merged["done"] == 10);
    CHECK_THROWS_WITH(
        merge_batch_reports(
            {shard_report(0, 2, 1, 0, 0, 0.0, 1.0), shard_report(0, 2, 1, 0, 0, 0.0, 1.0)}, 2),
        Catch::Contains("shard 0 reported twice"));
    CHECK_THROWS_WITH(merge_batch_reports({shard_report(0, 3, 1, 0, 0, 0.0, 1.0)}, 2),
                      Catch::Contains("expected 2 shards"));
    json no_cpu = shard_report(0, 1, 1, 0, 0, 0.0, 1.0);
    no_cpu.erase("cpu_seconds");
    CHECK_THROWS_WITH(merge_batch_reports({no_cpu}, 1), Catch::Contains("cpu_seconds"));
    CHECK_THROWS_WITH(merge_batch_reports({json{{"frames", 3}}}, 1),
                      Catch::Contains("not a shard report"));
    CHECK_THROWS_AS(merge_batch_reports({}, 0), std::invalid_argument);
}

TEST_CASE("no reports at all: every shard missing, nothing done", "[report]") {
    const json merged = merge_batch_reports({}, 2);
    CHECK(merged["missing_shards"] == json::array({0, 1}));
    CHECK(merged["frames"] == 0);
    CHECK(merged["fps"].get<double>() == 0.0);
}

TEST_CASE("disparity scores pool over pixels and merge exactly across shards", "[report]") {
    DisparityScore a;
    a.gt_pixels = 100;
    a.est_pixels = 80;
    a.d1_all = 0.5;
    a.epe_px = 2.0;
    DisparityScore b;
    b.gt_pixels = 300;
    b.est_pixels = 300;
    b.d1_all = 0.1;
    b.epe_px = 1.0;
    DisparityTally one;
    one.add(a);
    one.add(b);
    // Pooled, not the mean of 50 % and 10 %: (50 + 30) / 400.
    CHECK(one.to_json()["d1_all"].get<double>() == Approx(0.2));
    CHECK(one.to_json()["epe_px"].get<double>() == Approx((160.0 + 300.0) / 380.0));
    CHECK(one.to_json()["density"].get<double>() == Approx(0.95));

    json r0 = shard_report(0, 2, 1, 0, 0, 0.0, 1.0);
    json r1 = shard_report(1, 2, 1, 0, 0, 0.0, 1.0);
    DisparityTally ta, tb;
    ta.add(a);
    tb.add(b);
    r0["evaluation"] = ta.to_json();
    r1["evaluation"] = tb.to_json();
    const json merged = merge_batch_reports({r0, r1}, 2);
    REQUIRE(merged.contains("evaluation"));
    CHECK(merged["evaluation"]["frames"] == 2);
    CHECK(merged["evaluation"]["d1_all"].get<double>() == Approx(0.2));
    CHECK_FALSE(
        merge_batch_reports({shard_report(0, 1, 1, 0, 0, 0.0, 1.0)}, 1).contains("evaluation"));
    r1["evaluation"].erase("gt_pixels");
    CHECK_THROWS_WITH(merge_batch_reports({r0, r1}, 2), Catch::Contains("gt_pixels"));
}
