#pragma once

/// One report from the per-shard reports of a sharded batch (`cloud-analysis report`): frames
/// done, skipped by --resume and failed (with reasons), throughput, CPU time and memory, and
/// which shards are missing. The report fields are listed in docs/cli.md ("report").

#include <cstddef>
#include <vector>

#include <nlohmann/json.hpp>

#include "cloud_analysis/stereo/disparity.hpp"

namespace cloud_analysis {

/// Disparity scores of many frames as sums, so shards merge exactly: KITTI's D1-all pools the
/// outlier pixels of all frames over all ground-truth pixels (not a mean of per-frame ratios).
struct DisparityTally {
    std::size_t frames = 0;       ///< frames scored (those with ground truth)
    std::size_t gt_pixels = 0;    ///< pixels with a ground-truth value
    std::size_t est_pixels = 0;   ///< of those, pixels the estimate covers
    double outlier_pixels = 0.0;  ///< D1 outliers (missing estimates count), pixels
    double error_sum_px = 0.0;    ///< sum of |error| over est_pixels, px

    void add(const DisparityScore& score);
    void add(const DisparityTally& other);
    /// The sums plus d1_all, epe_px and density.
    nlohmann::json to_json() const;
    /// Reads the sums back; throws std::invalid_argument when one is missing.
    static DisparityTally from_json(const nlohmann::json& json);
};

/// Merges shard reports (each written by `batch --shard I/N --report`) of one run of `shards`
/// shards. Counts add up; wall_seconds spans the earliest start to the latest end, so fps is
/// the run's throughput however the shards were scheduled; fps_per_task is one task's
/// (done frames over the sum of the tasks' wall times); peak_rss_mb is the largest shard's.
/// When shards carry an "evaluation" (DisparityTally::to_json), the merged report has their sum.
/// Missing shards are listed in "missing_shards" (the caller decides whether that fails).
/// Throws std::invalid_argument when a report is not a shard report of this run or a shard
/// appears twice.
nlohmann::json merge_batch_reports(const std::vector<nlohmann::json>& reports, int shards);

}  // namespace cloud_analysis
