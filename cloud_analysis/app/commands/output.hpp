#pragma once

/// How the commands write what they made: whole files formatted in memory first, then each
/// written atomically (or to stdout for "-").

#include <string>

#include <stereoscene/support/atomic_file.hpp>

namespace cloud_analysis::app {

inline constexpr const char* kTool = "cloud-analysis";

/// One output file, formatted in memory before anything is written.
struct PendingOutput {
    std::string path;   ///< "-" = stdout
    std::string bytes;  ///< whole file
    std::string label;  ///< flag that asked for it (for --timings)
    /// Clouds are written without fsync unless --fsync-clouds (docs/cli.md "Durability").
    stereoscene::support::FileSync sync = stereoscene::support::FileSync::kDurable;
};

/// Writes one output atomically (or to stdout for "-").
void write_output(const PendingOutput& out);

}  // namespace cloud_analysis::app
