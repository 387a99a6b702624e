#pragma once

/// `cloud-analysis score-semantics`: a class image (e.g. --semantic-out of the stereo-only path)
/// against a ground-truth semantic image: pixel accuracy and per-class IoU.

#include <filesystem>
#include <string>
#include <vector>

#include <CLI/CLI.hpp>

namespace cloud_analysis::app {

/// Flags of `score-semantics`.
struct ScoreSemanticsArgs {
    std::filesystem::path estimate;  ///< semantic colour PNG to score
    std::filesystem::path truth;     ///< ground-truth semantic colour PNG, same size
    std::string palette = "cityscapes";
    std::vector<std::string> classes = {"road", "car", "building", "vegetation", "sky"};
    std::string json;  ///< "-" = JSON on stdout
};

CLI::App* add_score_semantics_command(CLI::App& app, ScoreSemanticsArgs& a);

int run_score_semantics(const ScoreSemanticsArgs& a);

}  // namespace cloud_analysis::app
