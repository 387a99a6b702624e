#pragma once

/// `cloud-analysis export-kitti`: an entity file as KITTI object label_2 lines, so KITTI's tools
/// can score it.

#include <filesystem>
#include <string>

#include <CLI/CLI.hpp>

namespace cloud_analysis::app {

/// Flags of `export-kitti`, filled by CLI11.
struct ExportKittiArgs {
    std::filesystem::path entities;  ///< positional: entity JSON file
    std::string output;              ///< -o: label_2 text file ("-" = stdout)
    std::filesystem::path calib;     ///< --calib: camera for alpha/2D boxes (else the file's)
};

/// Registers `export-kitti` on app and binds its flags to args.
CLI::App* add_export_kitti_command(CLI::App& app, ExportKittiArgs& args);

/// Writes the entities of a file as KITTI label_2 lines (atomically); returns 0. Throws like
/// run_evaluate.
int run_export_kitti(const ExportKittiArgs& args);

}  // namespace cloud_analysis::app
