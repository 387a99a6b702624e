#pragma once

/// `cloud-analysis track`: a drive's entity files (a batch's output folder or a sequence
/// index) tracked in order (cloud_analysis/tracking): track_id, velocity and smoothed boxes,
/// one entity file per frame plus sequence.json. `--bench-objects N` measures the tracker.

#include <filesystem>

#include <CLI/CLI.hpp>

#include "cloud_analysis/tracking/sequence.hpp"

namespace cloud_analysis::app {

/// Flags of `track`.
struct TrackArgs {
    std::filesystem::path input;    ///< folder of entity files or a sequence index
    std::filesystem::path out_dir;  ///< --out-dir: tracked files and sequence.json
    bool quiet = false;             ///< --quiet: no summary line
    int bench_objects = 0;          ///< --bench-objects: time the tracker on N objects instead
    int bench_frames = 300;         ///< --bench-frames: frames of that benchmark
    cloud_analysis::tracking::SequenceTrackOptions options;  ///< --fps, --min-hits, ...
};

/// Registers `track` on app and binds its flags to args (which must outlive parsing).
CLI::App* add_track_command(CLI::App& app, TrackArgs& args);

/// Tracks and writes; returns 0, or 1 when a frame could not be read (each named on stderr;
/// the other frames are written). Throws CLI::ValidationError for bad flags.
int run_track(const TrackArgs& args);

}  // namespace cloud_analysis::app
