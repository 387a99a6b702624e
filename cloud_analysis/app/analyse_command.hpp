#pragma once

/// The `analyse` command (the default) and what `batch` and `bench` share with it: the flags of
/// one analysis, their resolution into options, and one run from files to written outputs.

#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include <CLI/CLI.hpp>
#include <scene_schema/entities.hpp>

#include "cloud_analysis/entities/extract.hpp"
#include "cloud_analysis/pipeline/pipeline.hpp"
#include "cloud_analysis/stereo/disparity.hpp"

namespace cloud_analysis::app {

inline constexpr const char* kTool = "cloud-analysis";

/// Flags of `analyse` (the default command).
struct AnalyseArgs {
    cloud_analysis::InputPaths paths;
    std::filesystem::path kitti_root;
    std::string frame;
    cloud_analysis::AnalyseOptions options;
    std::string preset = "tuned";
    std::string method = "instances";
    std::filesystem::path class_config;
    std::string entities;
    std::filesystem::path xyz, pcd, ply, disparity_png, disparity_kitti, gt_disparity;
    std::filesystem::path semantic_out;  ///< --semantic-out: the classes used, as a PNG
    bool timings = false;
    bool fsync_clouds = false;  ///< --fsync-clouds: the clouds are durable too
    bool warnings = true;       ///< print the inputs' warnings (bench: on its first run only)
};

/// One output file, formatted in memory before anything is written.
struct PendingOutput {
    std::string path;   ///< "-" = stdout
    std::string bytes;  ///< whole file
    std::string label;  ///< flag that asked for it (for --timings)
    /// Clouds are written without fsync unless --fsync-clouds (docs/cli.md "Durability").
    stereoscene::support::FileSync sync = stereoscene::support::FileSync::kDurable;
};

/// Input flags of one frame (--left ... --kitti-root --frame).
void add_input_flags(CLI::App& cmd, AnalyseArgs& a);
/// Settings flags shared by analyse, batch and bench (palette, preset, SGBM, cloud, entities).
void add_settings_flags(CLI::App& cmd, AnalyseArgs& a);
/// Output flags of one frame (-o, --xyz, ..., --timings).
void add_output_flags(CLI::App& cmd, AnalyseArgs& a);

/// Applies the preset (flags given on `cmd` win) and validates; throws CLI::ValidationError.
void resolve_settings(AnalyseArgs& a, const CLI::App& cmd);
/// Resolves --kitti-root/--frame into paths, then the settings; throws CLI::ValidationError.
void resolve(AnalyseArgs& a, const CLI::App& cmd);

/// Writes one output atomically (or to stdout for "-").
void write_output(const PendingOutput& out);
/// How the cloud files are written: fsync'ed only with --fsync-clouds.
stereoscene::support::FileSync cloud_sync(const AnalyseArgs& a);

/// Extraction settings of the flags, with the class config read and validated.
cloud_analysis::ExtractOptions extract_options(const AnalyseArgs& a);

/// The analyse options for a run: without cloud outputs, analyse builds no cloud and
/// reprojects straight into the extractor's per-class points (AnalyseOptions::class_points_only).
cloud_analysis::AnalyseOptions options_for_outputs(const AnalyseArgs& a,
                                                   const cloud_analysis::ExtractOptions& extract,
                                                   const cloud_analysis::Palette& palette,
                                                   bool clouds);

/// The entity file of one analysed frame (entities, camera, `source` block), checked against
/// the schema, as text.
std::string entity_json(const cloud_analysis::LoadedInputs& in,
                        const cloud_analysis::AnalyseResult& r, const AnalyseArgs& a,
                        const cloud_analysis::ExtractOptions& extract);

/// What one run measured.
struct RunReport {
    std::vector<cloud_analysis::StageTiming> timings;  ///< load, disparity, ..., write per output
    std::size_t points = 0;                            ///< points in the cloud
};

/// What a run reads before its expensive stages: the decoded frame, the extraction settings
/// and the optional GT disparity.
struct LoadedRun {
    cloud_analysis::LoadedInputs inputs;                       ///< decoded images, calibration
    cloud_analysis::ExtractOptions extract;                    ///< with the class config read
    std::optional<cloud_analysis::DisparityMap> gt_disparity;  ///< --gt-disparity, when given
};

/// Checks the output flags and folders, reads the class config and the GT disparity, and
/// decodes and checks the inputs. Throws before anything expensive or written.
LoadedRun load_run(const AnalyseArgs& a);

/// The stages after decoding (disparity ... entity file and clouds written), with a matcher
/// kept across frames: a frame already in memory, as from a camera. Throws on failure, leaving
/// no output behind.
RunReport analyse_loaded_and_write(const LoadedRun& run, const AnalyseArgs& a,
                                   cloud_analysis::DisparityMatcher& matcher);

/// One analysis from files to written outputs (load_run, then analyse_loaded_and_write); the
/// first timing is "load". Throws on failure, leaving no output behind.
RunReport analyse_and_write(const AnalyseArgs& a, cloud_analysis::DisparityMatcher& matcher);

/// As above with a matcher of the run's own.
RunReport analyse_and_write(const AnalyseArgs& a);

/// `analyse`: analyse_and_write, then --timings to stderr. Returns the exit code.
int run_analyse(const AnalyseArgs& a);

}  // namespace cloud_analysis::app
