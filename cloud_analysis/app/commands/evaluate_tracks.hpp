#pragma once

/// `cloud-analysis evaluate-tracks`: scores a tracked drive (cloud-analysis track's output)
/// against a synthetic drive's truth (scene-render sensors --frames: truth/sequence.json and
/// visibility/) or KITTI tracking labels (label_02), with optional pass bars (exit 3).

#include <filesystem>

#include <CLI/CLI.hpp>

#include "cloud_analysis/evaluation/track_eval.hpp"

namespace cloud_analysis::app {

/// Flags of `evaluate-tracks`.
struct EvaluateTracksArgs {
    std::filesystem::path tracks;              ///< --tracks: tracked folder or its sequence.json
    std::filesystem::path truth;               ///< --truth: truth folder or its sequence.json
    std::filesystem::path kitti_labels;        ///< --kitti-labels: label_02/<drive>.txt
    double fps = 10.0;                         ///< --fps: KITTI labels' frame rate (velocities), Hz
    std::filesystem::path visibility;          ///< --visibility: folder of <frame>.json visibility
    double min_visible_fraction = 0.0;         ///< --min-visible-fraction: less visible = not owed
    cloud_analysis::TrackEvalOptions options;  ///< --match-distance, --eval-range
    cloud_analysis::TrackBars bars;            ///< --min-mota, ... (exit 3)
    bool events = false;  ///< --events: list every miss, false positive, switch and flip
};

/// Registers `evaluate-tracks` on app and binds its flags to args.
CLI::App* add_evaluate_tracks_command(CLI::App& app, EvaluateTracksArgs& args);

/// Prints the table to stdout; returns 0, or 3 after one stderr line per missed bar.
int run_evaluate_tracks(const EvaluateTracksArgs& args);

}  // namespace cloud_analysis::app
