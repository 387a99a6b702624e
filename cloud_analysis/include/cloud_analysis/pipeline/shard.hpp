#pragma once

/// Sharding of a batch's frame list: N shards (e.g. the tasks of a Slurm job array) together
/// process every frame exactly once, each shard a deterministic share. See docs/cluster.md.

#include <string>
#include <string_view>
#include <vector>

namespace cloud_analysis {

/// One share of a frame list: shard `index` of `count`.
struct Shard {
    int index = 0;  ///< this shard, 0 .. count-1
    int count = 1;  ///< number of shards the list is split into (1 = the whole list)

    /// Throws std::invalid_argument naming the bad field.
    void validate() const;
};

/// Parses "I/N" (e.g. "2/10"); throws std::invalid_argument saying what is wrong.
Shard parse_shard(std::string_view text);

/// The shard of a Slurm job array task: SLURM_ARRAY_TASK_ID / SLURM_ARRAY_TASK_COUNT, given
/// as the variables' values (nullptr = unset). Returns the whole list ({0, 1}) when neither is
/// set; throws std::invalid_argument when only one is, or when they do not make a shard (an
/// array not numbered 0..N-1, or a resubmitted subset: give --shard then).
Shard shard_from_slurm(const char* task_id, const char* task_count);

/// The frames of `shard`: frame i of the list goes to shard i mod count. Dealt round-robin
/// rather than in blocks, so a stretch of slow frames (a busy street in a sequence) is spread
/// over every shard; shares differ by at most one frame. Order within the share is kept.
std::vector<std::string> shard_frames(const std::vector<std::string>& frames, const Shard& shard);

}  // namespace cloud_analysis
