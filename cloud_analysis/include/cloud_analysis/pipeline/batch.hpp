#pragma once

/// Many frames of a KITTI-layout folder analysed in one process on three threads: while the
/// current frame is matched, the next one is decoded and the previous one's entities are
/// extracted and its files written. The matcher, the calibrations and the palette are kept
/// across frames. See docs/performance.md.

#include <cstddef>
#include <filesystem>
#include <functional>
#include <optional>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "cloud_analysis/entities/extract.hpp"
#include "cloud_analysis/odometry/visual_odometry.hpp"
#include "cloud_analysis/pipeline/batch_report.hpp"
#include "cloud_analysis/pipeline/drive.hpp"
#include "cloud_analysis/pipeline/entity_document.hpp"
#include "cloud_analysis/pipeline/pipeline.hpp"
#include "cloud_analysis/tracking/sequence.hpp"

namespace cloud_analysis {

/// Settings of run_batch.
struct BatchOptions {
    std::filesystem::path kitti_root;  ///< KITTI layout folder (image_2/, image_3/, ...)
    std::vector<std::string> frames;   ///< frame ids, analysed in this order
    bool kitti_instances = false;      ///< also read kitti_root's instance/<frame>.png
    /// Frames with their own files (a KITTI raw drive or a list of pairs), analysed in this
    /// order; when given, `frames` must hold their ids and kitti_root is not read.
    std::vector<DriveFrame> drive;
    /// Track the frames in order as they are written: entity files with track ids and
    /// out_dir/sequence.json, rewritten after every frame (tracking/sequence.hpp).
    std::optional<tracking::SequenceTrackOptions> track;
    std::string sequence_id = "drive";  ///< the index's id when tracking
    std::filesystem::path out_dir;      ///< <frame>.json (+ clouds) per frame; must exist
    /// The lock file in out_dir held while the batch writes (one writer of these frames at a
    /// time; shards of one list take one each, stereoscene::support::FolderLock).
    std::string lock_name = ".batch.lock";
    std::vector<std::string> cloud_formats;       ///< also <frame>.<fmt> for each of xyz, pcd, ply
    std::vector<std::string> cloud_drop_classes;  ///< classes left out of the clouds ("sky")
    bool disparity_kitti = false;                 ///< also <frame>_disparity.png (KITTI 16-bit)
    /// Estimate the camera's motion frame to frame (odometry/visual_odometry.hpp): each entity
    /// file's frame.pose and out_dir/poses.txt (KITTI odometry format, one line per frame
    /// written, in order). Needs the frames in order, as tracking does.
    bool odometry = false;
    odometry::OdometryOptions odometry_options;  ///< its settings
    bool fsync_clouds = false;                   ///< clouds fsync'ed too (entity files always are)
    /// Score each frame's disparity against <kitti_root>/disp_occ_0/<frame>.png when present.
    bool evaluate = false;
    ExtractOptions extract;  ///< entity extraction (class config read)
    RunSettings run;         ///< analysis settings, as the source block says
};

/// What a batch measured.
struct BatchReport {
    std::size_t frames = 0;  ///< frames asked for
    std::size_t failed = 0;  ///< frames that failed (nothing of them written)
    /// One {"frame", "error"} object per failed frame, in the order they failed.
    nlohmann::json failures = nlohmann::json::array();
    double seconds = 0.0;           ///< wall time of the frames, seconds
    double fps = 0.0;               ///< frames / seconds (0 without frames)
    double cpu_seconds = 0.0;       ///< process CPU time (all threads) of the frames, seconds
    double cpu_ms_per_frame = 0.0;  ///< cpu_seconds per frame, ms (0 without frames)
    unsigned cores = 1;             ///< hardware threads of the machine
    double cores_busy = 0.0;        ///< CPU time over wall time times cores, [0, 1]
    /// Per frame: frame, load_ms, wait_load_ms, per-stage <stage>_ms, points, analyse_ms,
    /// rss_mb, wait_finish_ms, finish_ms, and error when it failed.
    nlohmann::json per_frame = nlohmann::json::array();
    /// With BatchOptions::evaluate: the scores of the frames that had ground truth (per frame:
    /// d1_all and epe_px in per_frame, or evaluation_error when the truth could not be used).
    DisparityTally evaluation;
    /// With BatchOptions::track: frames tracked, tracks, restarts, tracker time.
    std::optional<tracking::SequenceTrackReport> tracking;
    /// With BatchOptions::odometry: the rig's disparity offset, px at full resolution: the
    /// analysis' own (CalibrationOptions::disparity_offset_px) plus what the odometry still
    /// measures from the drive's motion (docs/odometry.md); --disparity-offset takes it.
    std::optional<double> disparity_offset_px;
};

/// Called on the calling thread as the batch goes: failed(frame, reason) for each frame that
/// fails (the batch goes on), not_scored(frame, reason) for each frame whose ground truth could not
/// be used (with BatchOptions::evaluate), progress(done, total, failed, seconds) after each frame.
struct BatchObserver {
    std::function<void(const std::string& frame, const std::string& reason)> failed;
    std::function<void(const std::string& frame, const std::string& reason)> not_scored;
    std::function<void(std::size_t done, std::size_t total, std::size_t failed, double seconds)>
        progress;
    /// With tracking: the tracker's warnings ("<file>: <reason>"), called from the finishing
    /// thread.
    std::function<void(const std::string& warning)> warning;
};

/// Analyses every frame of options.frames and writes its files into options.out_dir, each
/// frame all or nothing and its entity file last (so a killed batch leaves each frame whole or
/// without its entity file). With options.track the finishing thread, which takes the frames
/// in order, tracks each frame before writing it and adds it to the index after. Throws before the
/// first frame when a folder is missing or the palette cannot be read; a frame that fails later is
/// reported to the observer and skipped.
BatchReport run_batch(const BatchOptions& options, const BatchObserver& observer);

/// What batch --odometry hands the odometry for an analysed frame: `left` (the frame's left
/// image, or another of its size), the frame's right image, both in grey, its disparity, and
/// its thing classes masked from voting (odometry::static_mask).
odometry::OdometryFrame odometry_frame(const ImageU8& left, const LoadedInputs& in,
                                       const AnalyseResult& r);

/// Peak resident set of this process so far, MB.
double peak_rss_mb();

}  // namespace cloud_analysis
