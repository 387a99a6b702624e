#pragma once

/// `cloud-analysis evaluate-odometry`: scores a drive's poses (batch --odometry's poses.txt)
/// against ground-truth poses (KITTI odometry's poses/NN.txt, scene-render sensors' truth) with
/// KITTI's odometry metric, and optional pass bars (exit 3).

#include <filesystem>
#include <optional>
#include <string>

#include <CLI/CLI.hpp>

namespace cloud_analysis::app {

/// Flags of `evaluate-odometry`.
struct EvaluateOdometryArgs {
    std::filesystem::path poses;                   ///< --poses: the estimate, KITTI poses text
    std::filesystem::path truth;                   ///< --truth: the same frames' true poses
    std::string json;                              ///< --json: also the scores as JSON ("-")
    std::optional<double> max_translation_pct;     ///< --max-translation-error: bar, %
    std::optional<double> max_end_point_pct;       ///< --max-end-point-error: bar, % of the path
    std::optional<double> max_rotation_deg_per_m;  ///< --max-rotation-error: bar, deg/m
};

/// Registers `evaluate-odometry` on app and binds its flags to args.
CLI::App* add_evaluate_odometry_command(CLI::App& app, EvaluateOdometryArgs& args);

/// Prints the table to stdout; returns 0, or 3 after one stderr line per missed bar.
int run_evaluate_odometry(const EvaluateOdometryArgs& args);

}  // namespace cloud_analysis::app
