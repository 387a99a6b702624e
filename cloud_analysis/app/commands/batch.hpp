#pragma once

/// `cloud-analysis batch`: many frames in one process (cloud_analysis::run_batch) from a
/// KITTI-layout root, a KITTI raw drive or a list of pairs, tracked in order on request,
/// a share of the list (--shard, or a Slurm array task's), --resume, progress and failures on
/// stderr, an optional JSON report. See docs/performance.md and docs/cluster.md.

#include <cstddef>
#include <filesystem>
#include <string>
#include <vector>

#include <CLI/CLI.hpp>

#include "analysis_flags.hpp"
#include "cloud_analysis/pipeline/drive.hpp"
#include "cloud_analysis/pipeline/shard.hpp"
#include "cloud_analysis/tracking/sequence.hpp"

namespace cloud_analysis::app {

/// Flags of `batch`.
struct BatchArgs {
    AnalyseArgs settings;              ///< palette, preset, SGBM, cloud and entity flags
    std::filesystem::path kitti_root;  ///< --kitti-root: KITTI layout folder
    std::filesystem::path drive_dir;   ///< --drive: KITTI raw drive folder
    std::filesystem::path pairs;       ///< --pairs: file of LEFT RIGHT [SEMANTIC [INSTANCE]] lines
    std::filesystem::path calib;       ///< --calib: the calibration of --drive / --pairs
    std::filesystem::path semantic_dir;  ///< --semantic-dir: a drive's semantic images
    std::filesystem::path instance_dir;  ///< --instance-dir: a drive's instance images
    bool instances = false;              ///< --instances: a KITTI root's instance/<frame>.png
    std::vector<cloud_analysis::DriveFrame> drive;  ///< the frames of --drive or --pairs
    bool track = false;                             ///< --track: track ids + sequence.json
    bool odometry = false;                          ///< --odometry: poses.txt + frame.pose
    bool fixed_disparity_offset = false;  ///< --no-disparity-offset: the disparities as they are
    tracking::SequenceTrackOptions track_options;  ///< --fps, --min-hits, --max-misses
    std::vector<std::string> frames;               ///< --frames: frame ids
    std::filesystem::path list;                    ///< --list: file of frame ids, one per line
    std::filesystem::path out_dir;                 ///< --out-dir: <frame>.json (+ clouds) per frame
    std::vector<std::string> cloud_formats;        ///< --clouds: any of xyz pcd ply
    bool disparity_kitti = false;                  ///< --disparity-kitti: <frame>_disparity.png
    std::filesystem::path report;                  ///< --report: per-frame ms and memory as JSON
    std::string shard_text;          ///< --shard: "I/N" (else from SLURM_ARRAY_TASK_*)
    cloud_analysis::Shard shard;     ///< the share of the list this run does
    std::size_t list_frames = 0;     ///< frames in the whole list, before sharding
    bool resume = false;             ///< --resume: skip frames already complete and valid
    bool quiet = false;              ///< --quiet: no progress, no summary line
    bool evaluate = false;           ///< --evaluate: score disparity where GT exists
    double progress_every_s = 10.0;  ///< --progress-every: seconds between log lines
};

/// Registers `batch` on app and binds its flags to args (which must outlive parsing).
CLI::App* add_batch_command(CLI::App& app, BatchArgs& args);

/// Resolves the frame list, the share and the settings; throws CLI::ValidationError.
void resolve_batch(BatchArgs& args, const CLI::App& cmd);

/// Exit code 0 when every frame succeeded, 1 when any failed (each named on stderr).
int run_batch(const BatchArgs& args);

}  // namespace cloud_analysis::app
