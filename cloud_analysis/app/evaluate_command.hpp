#pragma once

/// The `cloud-analysis evaluate` subcommand: scores a run against KITTI-style ground truth
/// (disparity vs disp_occ_0; car entities vs the instance images' cars) and prints a table.

#include <filesystem>
#include <string>

#include <CLI/CLI.hpp>

namespace cloud_analysis::app {

/// Flags of `evaluate`, filled by CLI11.
struct EvaluateArgs {
    std::filesystem::path entities;    ///< --entities: entity JSON to score (cars)
    std::filesystem::path disparity;   ///< --disparity: our KITTI 16-bit disparity PNG
    std::filesystem::path kitti_root;  ///< --kitti-root: folder with calib/, instance/, ...
    std::string frame;                 ///< --frame: frame id, e.g. 000000_10
    std::filesystem::path
        gt_disparity;                ///< --gt-disparity: overrides <root>/disp_occ_0/<frame>.png
    std::filesystem::path instance;  ///< --instance: overrides <root>/instance/<frame>.png
    std::filesystem::path calib;     ///< --calib: overrides <root>/calib/calib_cam_to_cam.txt
    std::filesystem::path json;      ///< --json: also write the scores as JSON ("-" = stdout)
    double max_range_m = 30.0;       ///< --max-range: cars farther than this are ignored, m
    int min_gt_pixels = 200;         ///< --min-gt-pixels: GT cars owed for recall
};

/// Registers `evaluate` on app and binds its flags to args (which must outlive parsing).
/// main() runs run_evaluate(args) when the returned subcommand was parsed (`if (*sub)`).
CLI::App* add_evaluate_command(CLI::App& app, EvaluateArgs& args);

/// Runs the evaluation: table to stdout (to stderr when --json is "-"), JSON to --json.
/// Throws CLI::ValidationError for inconsistent flags (map to exit 2) and std::exception
/// for failures (map to exit 1, message "<what failed>: <detail> (<file>)").
void run_evaluate(const EvaluateArgs& args);

}  // namespace cloud_analysis::app
