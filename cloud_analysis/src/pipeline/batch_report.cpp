#include "cloud_analysis/pipeline/batch_report.hpp"

#include <algorithm>
#include <limits>
#include <map>
#include <stdexcept>
#include <string>
#include <utility>

namespace cloud_analysis {
namespace {

/// The number under `key`, or `fallback` when absent or not a number.
double number_or(const nlohmann::json& object, const char* key, double fallback) {
    const auto it = object.find(key);
    return it != object.end() && it->is_number() ? it->get<double>() : fallback;
}

/// The string under `key`, or `fallback` when absent or not a string.
std::string string_or(const nlohmann::json& object, const char* key, const std::string& fallback) {
    const auto it = object.find(key);
    return it != object.end() && it->is_string() ? it->get<std::string>() : fallback;
}

/// The shard index of a report of a run of `shards` shards; throws otherwise.
int shard_index(const nlohmann::json& report, int shards, std::size_t position) {
    const std::string which = "report " + std::to_string(position + 1);
    if (!report.is_object() || !report.contains("shard") || !report["shard"].is_object()) {
        throw std::invalid_argument(which + ": not a shard report (no 'shard' object)");
    }
    const int index = static_cast<int>(number_or(report["shard"], "index", -1.0));
    const int count = static_cast<int>(number_or(report["shard"], "count", -1.0));
    if (count != shards) {
        throw std::invalid_argument(which + ": shard of " + std::to_string(count) + ", expected " +
                                    std::to_string(shards) + " shards");
    }
    if (index < 0 || index >= shards) {
        throw std::invalid_argument(which + ": shard index " + std::to_string(index) +
                                    " out of range");
    }
    for (const char* key : {"frames", "done", "skipped", "failed", "seconds", "cpu_seconds",
                            "peak_rss_mb", "started_at", "ended_at"}) {
        if (!report.contains(key) || !report[key].is_number()) {
            throw std::invalid_argument(which + ": no number '" + key + "'");
        }
    }
    return index;
}

}  // namespace

void DisparityTally::add(const DisparityScore& score) {
    ++frames;
    gt_pixels += score.gt_pixels;
    est_pixels += score.est_pixels;
    outlier_pixels += score.d1_all * static_cast<double>(score.gt_pixels);
    error_sum_px += score.epe_px * static_cast<double>(score.est_pixels);
}

void DisparityTally::add(const DisparityTally& other) {
    frames += other.frames;
    gt_pixels += other.gt_pixels;
    est_pixels += other.est_pixels;
    outlier_pixels += other.outlier_pixels;
    error_sum_px += other.error_sum_px;
}

nlohmann::json DisparityTally::to_json() const {
    const auto ratio = [](double num, std::size_t den) {
        return den > 0 ? num / static_cast<double>(den) : 0.0;
    };
    return {{"frames", frames},
            {"gt_pixels", gt_pixels},
            {"est_pixels", est_pixels},
            {"outlier_pixels", outlier_pixels},
            {"error_sum_px", error_sum_px},
            {"d1_all", ratio(outlier_pixels, gt_pixels)},
            {"epe_px", ratio(error_sum_px, est_pixels)},
            {"density", ratio(static_cast<double>(est_pixels), gt_pixels)}};
}

DisparityTally DisparityTally::from_json(const nlohmann::json& json) {
    for (const char* key :
         {"frames", "gt_pixels", "est_pixels", "outlier_pixels", "error_sum_px"}) {
        if (!json.is_object() || !json.contains(key) || !json[key].is_number()) {
            throw std::invalid_argument(std::string("evaluation: no number '") + key + "'");
        }
    }
    DisparityTally t;
    t.frames = json["frames"].get<std::size_t>();
    t.gt_pixels = json["gt_pixels"].get<std::size_t>();
    t.est_pixels = json["est_pixels"].get<std::size_t>();
    t.outlier_pixels = json["outlier_pixels"].get<double>();
    t.error_sum_px = json["error_sum_px"].get<double>();
    return t;
}

/// One shard's line of the merged report's per_shard.
nlohmann::json shard_summary(int index, const nlohmann::json& r) {
    return {{"index", index},
            {"frames", r["frames"]},
            {"done", r["done"]},
            {"skipped", r["skipped"]},
            {"failed", r["failed"]},
            {"seconds", r["seconds"]},
            {"fps", number_or(r, "fps", 0.0)},
            {"peak_rss_mb", r["peak_rss_mb"]}};
}

nlohmann::json merge_batch_reports(const std::vector<nlohmann::json>& reports, int shards) {
    if (shards < 1) throw std::invalid_argument("shards: must be >= 1");
    std::map<int, const nlohmann::json*> by_index;
    for (std::size_t i = 0; i < reports.size(); ++i) {
        const int index = shard_index(reports[i], shards, i);
        if (!by_index.emplace(index, &reports[i]).second) {
            throw std::invalid_argument("shard " + std::to_string(index) + " reported twice");
        }
    }
    std::size_t frames = 0, done = 0, skipped = 0, failed = 0, warned = 0;
    double task_seconds = 0.0, cpu_seconds = 0.0, peak_rss_mb = 0.0;
    double started = std::numeric_limits<double>::infinity();
    double ended = -std::numeric_limits<double>::infinity();
    std::vector<std::pair<std::string, std::string>> failures;  // frame, error
    nlohmann::json per_shard = nlohmann::json::array();
    nlohmann::json missing = nlohmann::json::array();
    std::string preset;
    DisparityTally evaluation;
    bool evaluated = false;
    for (int index = 0; index < shards; ++index) {
        const auto it = by_index.find(index);
        if (it == by_index.end()) {
            missing.push_back(index);
            continue;
        }
        const nlohmann::json& r = *it->second;
        frames += r["frames"].get<std::size_t>();
        done += r["done"].get<std::size_t>();
        skipped += r["skipped"].get<std::size_t>();
        failed += r["failed"].get<std::size_t>();
        warned += static_cast<std::size_t>(number_or(r, "frames_with_warnings", 0.0));
        task_seconds += r["seconds"].get<double>();
        cpu_seconds += r["cpu_seconds"].get<double>();
        peak_rss_mb = std::max(peak_rss_mb, r["peak_rss_mb"].get<double>());
        started = std::min(started, r["started_at"].get<double>());
        ended = std::max(ended, r["ended_at"].get<double>());
        if (r.contains("failures") && r["failures"].is_array()) {
            for (const auto& f : r["failures"]) {
                if (!f.is_object()) continue;
                failures.emplace_back(string_or(f, "frame", "?"), string_or(f, "error", "?"));
            }
        }
        if (r.contains("evaluation")) {
            evaluation.add(DisparityTally::from_json(r["evaluation"]));
            evaluated = true;
        }
        const std::string p = string_or(r, "preset", "");
        preset = preset.empty() || preset == p ? p : "mixed";
        per_shard.push_back(shard_summary(index, r));
    }
    std::sort(failures.begin(), failures.end());
    nlohmann::json failure_list = nlohmann::json::array();
    for (const auto& [frame, error] : failures) {
        failure_list.push_back({{"frame", frame}, {"error", error}});
    }
    const double wall = by_index.empty() ? 0.0 : ended - started;
    const auto per = [](double num, double den) { return den > 0.0 ? num / den : 0.0; };
    nlohmann::json merged = {
        {"shards", shards},
        {"shards_reported", by_index.size()},
        {"missing_shards", missing},
        {"frames", frames},
        {"done", done},
        {"skipped", skipped},
        {"failed", failed},
        {"failures", failure_list},
        {"frames_with_warnings", warned},
        {"wall_seconds", wall},
        {"fps", per(static_cast<double>(done), wall)},
        {"task_seconds", task_seconds},
        {"fps_per_task", per(static_cast<double>(done), task_seconds)},
        {"cpu_seconds", cpu_seconds},
        {"cpu_ms_per_frame", 1000.0 * per(cpu_seconds, static_cast<double>(done))},
        {"peak_rss_mb", peak_rss_mb},
        {"preset", preset},
        {"per_shard", per_shard}};
    if (evaluated) merged["evaluation"] = evaluation.to_json();
    return merged;
}

}  // namespace cloud_analysis
