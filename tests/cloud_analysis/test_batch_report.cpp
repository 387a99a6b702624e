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

TEST_CASE("a missing shard is listed; a duplicate or foreign report is refused", "[report]") {
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
