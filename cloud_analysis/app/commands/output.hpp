#pragma once

/// How the commands check their input files and write what they made: whole files formatted in
/// memory first, then each written atomically (or to stdout for "-").

#include <filesystem>
#include <string>
#include <string_view>
#include <vector>

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

/// Throws "cannot <action>: no such file (<path>)" (or "not a regular file") for the first of
/// `inputs` that is not a regular file; empty paths and "-" (stdin) pass.
void require_input_files(const std::vector<std::filesystem::path>& inputs, std::string_view action);

/// Writes one output atomically (or to stdout for "-").
void write_output(const PendingOutput& out);

}  // namespace cloud_analysis::app
