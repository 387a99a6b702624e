#pragma once

/// `cloud-analysis bench`: per-stage medians of the real run (entities; entities + all three
/// clouds), for a frame already in memory and for one read from PNG files, beside the OpenCV
/// matcher alone on the same input, as JSON. See docs/performance.md.

#include <filesystem>
#include <string>

#include <CLI/CLI.hpp>

#include "analysis_flags.hpp"

namespace cloud_analysis::app {

/// Flags of `bench`.
struct BenchArgs {
    AnalyseArgs analyse;             ///< inputs and settings of the frame
    int runs = 5;                    ///< --runs: timed runs per row (median)
    int warmup = 1;                  ///< --warmup: untimed runs first
    std::filesystem::path work_dir;  ///< --work-dir: where the timed outputs are written
    std::string json = "-";          ///< --json: result file ("-" = stdout)
    /// --next-left: the next frame's left image; also times the odometry's cost per frame.
    std::filesystem::path next_left;
    /// --prev-left, --prev-right: the frame before this one in the drive; the odometry starts
    /// from it, so the timed frame's tracks start from the drive's motion, as in a batch.
    std::filesystem::path prev_left, prev_right;
};

/// Registers `bench` on app and binds its flags to args (which must outlive parsing).
CLI::App* add_bench_command(CLI::App& app, BenchArgs& args);

/// Times the rows and writes the JSON result; returns the exit code (0).
int run_bench(const BenchArgs& args);

}  // namespace cloud_analysis::app
