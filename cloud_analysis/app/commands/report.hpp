#pragma once

/// `cloud-analysis report`: merges the reports of a sharded batch (batch --shard I/N --report)
/// into one. See docs/cluster.md.

#include <filesystem>
#include <string>
#include <vector>

#include <CLI/CLI.hpp>

namespace cloud_analysis::app {

/// Flags of `report`.
struct ReportArgs {
    std::vector<std::filesystem::path> inputs;  ///< positional: shard reports of one run
    int shards = 0;                             ///< --shards: shards of the run (0 = from reports)
    std::string output = "-";                   ///< -o: merged report ("-" = stdout)
};

/// Registers `report` on app and binds its flags to args (which must outlive parsing).
CLI::App* add_report_command(CLI::App& app, ReportArgs& args);

/// Merges shard reports; exit 1 (after writing the report) when a shard is missing or a frame
/// failed, each named on stderr.
int run_report(const ReportArgs& args);

}  // namespace cloud_analysis::app
