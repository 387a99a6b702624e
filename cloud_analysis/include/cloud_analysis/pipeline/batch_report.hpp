#pragma once

/// One report from the per-shard reports of a sharded batch (`cloud-analysis report`): frames
/// done, skipped by --resume and failed (with reasons), throughput, CPU time and memory, and
/// which shards are missing. The report fields are listed in docs/cli.md ("report").

#include <vector>

#include <nlohmann/json.hpp>

namespace cloud_analysis {

/// Merges shard reports (each written by `batch --shard I/N --report`) of one run of `shards`
/// shards. Counts add up; wall_seconds spans the earliest start to the latest end, so fps is
/// the run's throughput however the shards were scheduled; fps_per_task is one task's
/// (done frames over the sum of the tasks' wall times); peak_rss_mb is the largest shard's.
/// Missing shards are listed in "missing_shards" (the caller decides whether that fails).
/// Throws std::invalid_argument when a report is not a shard report of this run or a shard
/// appears twice.
nlohmann::json merge_batch_reports(const std::vector<nlohmann::json>& reports, int shards);

}  // namespace cloud_analysis
