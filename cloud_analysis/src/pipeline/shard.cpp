#include "cloud_analysis/pipeline/shard.hpp"

#include <charconv>
#include <stdexcept>
#include <string>

namespace cloud_analysis {
namespace {

/// A whole non-negative decimal number, or -1.
int parse_count(std::string_view text) {
    int value = -1;
    const char* end = text.data() + text.size();
    const auto [ptr, ec] = std::from_chars(text.data(), end, value);
    if (text.empty() || ec != std::errc() || ptr != end || value < 0) return -1;
    return value;
}

}  // namespace

void Shard::validate() const {
    if (count < 1) throw std::invalid_argument("shard count: must be >= 1");
    if (index < 0 || index >= count) {
        throw std::invalid_argument("shard index: must be in 0.." + std::to_string(count - 1));
    }
}

Shard parse_shard(std::string_view text) {
    const auto slash = text.find('/');
    const std::string what = "'" + std::string(text) + "'";
    if (slash == std::string_view::npos) {
        throw std::invalid_argument("expected I/N (shard I of N, I from 0), got " + what);
    }
    Shard s;
    s.index = parse_count(text.substr(0, slash));
    s.count = parse_count(text.substr(slash + 1));
    if (s.index < 0 || s.count < 0) {
        throw std::invalid_argument("expected I/N with whole numbers, got " + what);
    }
    s.validate();
    return s;
}

Shard shard_from_slurm(const char* task_id, const char* task_count) {
    if (task_id == nullptr && task_count == nullptr) return {};
    if (task_id == nullptr || task_count == nullptr) {
        throw std::invalid_argument(
            "SLURM_ARRAY_TASK_ID and SLURM_ARRAY_TASK_COUNT must both be set (or give --shard)");
    }
    Shard s;
    s.index = parse_count(task_id);
    s.count = parse_count(task_count);
    if (s.index < 0 || s.count < 1 || s.index >= s.count) {
        throw std::invalid_argument("SLURM_ARRAY_TASK_ID " + std::string(task_id) +
                                    " is not a shard of SLURM_ARRAY_TASK_COUNT " + task_count +
                                    " (arrays must be numbered 0..N-1; give --shard I/N)");
    }
    return s;
}

std::vector<std::string> shard_frames(const std::vector<std::string>& frames, const Shard& shard) {
    shard.validate();
    std::vector<std::string> share;
    share.reserve(frames.size() / static_cast<std::size_t>(shard.count) + 1);
    for (std::size_t i = static_cast<std::size_t>(shard.index); i < frames.size();
         i += static_cast<std::size_t>(shard.count)) {
        share.push_back(frames[i]);
    }
    return share;
}

}  // namespace cloud_analysis
