#pragma once

/// `cloud-analysis batch` (many frames in one process: matcher, buffers, calibration and palette
/// kept; the next frame decoded and the previous one written while the current one is matched)
/// and `cloud-analysis bench` (per-stage medians of the real run, for a frame already in memory
/// and for one read from PNG files, beside the OpenCV matcher alone on the same input, as JSON).
/// See docs/performance.md.

#include <filesystem>
#include <string>
#include <vector>

#include <CLI/CLI.hpp>

#include "analyse_command.hpp"
#include "cloud_analysis/pipeline/shard.hpp"

namespace cloud_analysis::app {

/// Flags of `batch`.
struct BatchArgs {
    AnalyseArgs settings;                    ///< palette, preset, SGBM, cloud and entity flags
    std::filesystem::path kitti_root;        ///< --kitti-root: KITTI layout folder
    std::vector<std::string> frames;         ///< --frames: frame ids
    std::filesystem::path list;              ///< --list: file of frame ids, one per line
    std::filesystem::path out_dir;           ///< --out-dir: <frame>.json (+ clouds) per frame
    std::vector<std::string> cloud_formats;  ///< --clouds: any of xyz pcd ply
    bool disparity_kitti = false;            ///< --disparity-kitti: <frame>_disparity.png
    std::filesystem::path report;            ///< --report: per-frame ms and memory as JSON
    std::string shard_text;                  ///< --shard: "I/N" (else from SLURM_ARRAY_TASK_*)
    cloud_analysis::Shard shard;             ///< the share of the list this run does
    std::size_t list_frames = 0;             ///< frames in the whole list, before sharding
    bool resume = false;                     ///< --resume: skip frames already complete and valid
    bool quiet = false;                      ///< --quiet: no progress, no summary line
    bool evaluate = false;                   ///< --evaluate: score disparity where GT exists
    double progress_every_s = 10.0;          ///< --progress-every: seconds between log lines
};

/// Flags of `bench`.
struct BenchArgs {
    AnalyseArgs analyse;             ///< inputs and settings of the frame
    int runs = 5;                    ///< --runs: timed runs per row (median)
    int warmup = 1;                  ///< --warmup: untimed runs first
    std::filesystem::path work_dir;  ///< --work-dir: where the timed outputs are written
    std::string json = "-";          ///< --json: result file ("-" = stdout)
};

/// Flags of `report`.
struct ReportArgs {
    std::vector<std::filesystem::path> inputs;  ///< positional: shard reports of one run
    int shards = 0;                             ///< --shards: shards of the run (0 = from reports)
    std::string output = "-";                   ///< -o: merged report ("-" = stdout)
};

CLI::App* add_batch_command(CLI::App& app, BatchArgs& args);
CLI::App* add_report_command(CLI::App& app, ReportArgs& args);
CLI::App* add_bench_command(CLI::App& app, BenchArgs& args);

/// Resolves the frame list and the settings; throws CLI::ValidationError.
void resolve_batch(BatchArgs& args, const CLI::App& cmd);

/// Exit code 0 when every frame succeeded, 1 when any failed (each named on stderr).
int run_batch(const BatchArgs& args);
int run_bench(const BenchArgs& args);
/// Merges shard reports; exit 1 (after writing the report) when a shard is missing or a frame
/// failed, each named on stderr.
int run_report(const ReportArgs& args);

}  // namespace cloud_analysis::app
