#pragma once

/// `cloud-analysis make-sample`: renders the synthetic street scene (stereo pair, semantics,
/// calibration, ground truth) into a folder; samples/synthetic is made this way.

#include <filesystem>

#include <CLI/CLI.hpp>

#include "cloud_analysis/synthetic/synthetic.hpp"

namespace cloud_analysis::app {

/// Flags of `make-sample`.
struct SampleArgs {
    std::filesystem::path out;                 ///< --out: output folder
    cloud_analysis::SyntheticOptions options;  ///< --seed, --width, --height, --fx
};

/// Registers `make-sample` on app and binds its flags to args (which must outlive parsing).
CLI::App* add_make_sample_command(CLI::App& app, SampleArgs& args);

/// Renders the scene and writes the sample's files (each encoded first); returns 0.
int run_make_sample(const SampleArgs& args);

}  // namespace cloud_analysis::app
