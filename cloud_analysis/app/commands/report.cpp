#include "report.hpp"

#include <cstdio>
#include <fstream>
#include <stdexcept>

#include <nlohmann/json.hpp>

#include "cloud_analysis/pipeline/batch_report.hpp"
#include "output.hpp"
#include "stereoscene/support/error_line.hpp"

namespace cloud_analysis::app {

CLI::App* add_report_command(CLI::App& app, ReportArgs& a) {
    CLI::App* cmd = app.add_subcommand(
        "report",
        "merge the reports of a sharded batch (batch --shard I/N --report) into one: frames "
        "done, skipped, failed with reasons, fps, CPU time, memory");
    cmd->add_option("reports", a.inputs, "shard report files")->required();
    cmd->add_option("--shards", a.shards, "shards of the run (default: as the reports say)")
        ->check(CLI::Range(1, 1000000));
    cmd->add_option("-o,--output", a.output, "merged report ('-' = stdout)")->capture_default_str();
    cmd->footer(
        "Exit 1 when a shard's report is missing or a frame failed (the report is "
        "still written), 2 on usage errors.");
    return cmd;
}

int run_report(const ReportArgs& a) {
    std::vector<nlohmann::json> reports;
    for (const auto& path : a.inputs) {
        std::ifstream in(path);
        if (!in)
            throw std::runtime_error("cannot read report: no such file (" + path.string() + ")");
        try {
            reports.push_back(nlohmann::json::parse(in));
        } catch (const nlohmann::json::exception& e) {
            throw std::runtime_error("cannot read report: " + std::string(e.what()) + " (" +
                                     path.string() + ")");
        }
    }
    int shards = a.shards;
    if (shards == 0 && !reports.empty() && reports.front().contains("shard")) {
        shards = reports.front()["shard"].value("count", 0);
    }
    nlohmann::json merged;
    try {
        merged = merge_batch_reports(reports, shards);
    } catch (const std::invalid_argument& e) {
        throw std::runtime_error(std::string("cannot merge reports: ") + e.what());
    }
    const std::string output_dir = std::filesystem::path(a.output).parent_path().string();
    if (a.output != "-" && !output_dir.empty() && !std::filesystem::is_directory(output_dir)) {
        throw std::runtime_error("cannot write output: no such folder (" + output_dir + ", -o)");
    }
    write_output({a.output, merged.dump(1) + "\n", "-o"});
    const nlohmann::json& m = merged;  // read only from here on
    for (const auto& index : m["missing_shards"]) {
        std::fprintf(stderr, "%s: error: shard %d/%d: no report\n", kTool, index.get<int>(),
                     shards);
    }
    for (const auto& f : m["failures"]) {
        const std::string line = stereoscene::support::error_line_of(
            kTool, "frame " + f.value("frame", "?"), f.value("error", "?"));
        std::fprintf(stderr, "%s\n", line.c_str());
    }
    std::fprintf(stderr,
                 "%s: report: %zu shards of %d, %zu frames: %zu done, %zu skipped (done "
                 "before), %zu failed; %.2f fps over %.1f s, %.0f ms CPU per frame, peak RSS "
                 "%.0f MB\n",
                 kTool, m["shards_reported"].get<std::size_t>(), shards,
                 m["frames"].get<std::size_t>(), m["done"].get<std::size_t>(),
                 m["skipped"].get<std::size_t>(), m["failed"].get<std::size_t>(),
                 m["fps"].get<double>(), m["wall_seconds"].get<double>(),
                 m["cpu_ms_per_frame"].get<double>(), m["peak_rss_mb"].get<double>());
    if (m["frames_with_warnings"].get<std::size_t>() > 0) {
        std::fprintf(
            stderr,
            "%s: report: %zu frames warned (their warnings are in the shard reports' per_frame)\n",
            kTool, m["frames_with_warnings"].get<std::size_t>());
    }
    if (merged.contains("evaluation")) {
        const auto& e = m["evaluation"];
        std::fprintf(stderr,
                     "%s: report: disparity over %zu frames with ground truth: D1-all %.2f %%, "
                     "EPE %.2f px, density %.1f %%\n",
                     kTool, e["frames"].get<std::size_t>(), 100.0 * e["d1_all"].get<double>(),
                     e["epe_px"].get<double>(), 100.0 * e["density"].get<double>());
    }
    return m["missing_shards"].empty() && m["failed"].get<std::size_t>() == 0 ? 0 : 1;
}

}  // namespace cloud_analysis::app
