#pragma once

/// The flags of one analysis, shared by `analyse`, `batch` and `bench`: inputs, settings
/// (palette, preset, SGBM, cloud, entities) and outputs, and their resolution into the
/// library's options.

#include <filesystem>
#include <string>
#include <vector>

#include <CLI/CLI.hpp>
#include <scene_schema/entities.hpp>
#include <stereoscene/support/atomic_file.hpp>

#include "cloud_analysis/entities/extract.hpp"
#include "cloud_analysis/pipeline/entity_document.hpp"
#include "cloud_analysis/pipeline/pipeline.hpp"

namespace cloud_analysis::app {

/// Flags of `analyse` (the default command).
struct AnalyseArgs {
    cloud_analysis::InputPaths paths;
    std::filesystem::path kitti_root;
    bool kitti_instances = false;  ///< --instances: the KITTI root's instance/<frame>.png
    std::string frame;
    cloud_analysis::AnalyseOptions options;
    std::string preset = "tuned";
    std::string method = "instances";
    std::string row_model = "partition";
    std::filesystem::path class_config;
    std::string entities;
    std::filesystem::path xyz, pcd, ply, disparity_png, disparity_kitti, gt_disparity;
    std::filesystem::path semantic_out;     ///< --semantic-out: the classes used, as a PNG
    std::filesystem::path segments_out;     ///< --segments-out: the stereo-only segments, JSON
    std::filesystem::path segment_ids_out;  ///< --segment-ids-out: their pixels, 16-bit PNG
    std::vector<std::string>
        drop_classes;             ///< --drop-classes (+ sky with --drop-sky): not in clouds
    bool drop_sky = false;        ///< --drop-sky
    bool no_rig_scaling = false;  ///< --no-rig-scaling: pixel settings as written for KITTI
    int point_lattice = 0;        ///< --point-lattice: things' pixel lattice step, 0 = the rig's
    /// --vehicle-classifier: "default" (the project's model), "none" (the rules) or a file.
    std::string vehicle_classifier = "default";
    /// --person-classifier: "default" (the project's model), "none" (the rules) or a file.
    std::string person_classifier = "default";
    bool timings = false;
    bool fsync_clouds = false;  ///< --fsync-clouds: the clouds are durable too
    bool warnings = true;       ///< print the inputs' warnings (bench: on its first run only)
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

/// How the cloud files are written: fsync'ed only with --fsync-clouds.
stereoscene::support::FileSync cloud_sync(const AnalyseArgs& a);

/// Extraction settings of the flags, with the class config read and validated.
cloud_analysis::ExtractOptions extract_options(const AnalyseArgs& a);

/// What the entity file's source block records of the flags: the analysis settings, the class
/// config ("default" for the bundled one) and the tool's version.
cloud_analysis::RunSettings run_settings(const AnalyseArgs& a);

}  // namespace cloud_analysis::app
