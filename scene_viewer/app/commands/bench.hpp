#pragma once

/// `bench`: frame times of a synthetic street scene, one row per shading.

#include <string>

#include "common.hpp"
#include "scene_viewer/bench/benchmark.hpp"

namespace scene_render {

struct BenchArgs {
    scene_viewer::BenchmarkOptions options;  ///< frames, cars, PNG level
    std::string size = "1280x720";           ///< image size WxH, pixels
    int msaa = 4;                            ///< samples of the "lit msaa" row; 0..1: no row
    bool boxes = false;                      ///< boxes instead of glTF models
};

CLI::App* add_bench_command(CLI::App& app, BenchArgs& args);

/// Prints the table on stdout; throws Failure.
int run_bench(const BenchArgs& args);

}  // namespace scene_render
