#pragma once

/// `cloud-analysis evaluate`: scores a run against KITTI-style ground truth (disparity vs
/// disp_occ_0; car entities vs the instance images' cars) or entity-to-entity against a
/// reference entity file / KITTI label_2 file, or in the image against 2D boxes, with optional pass
/// bars (exit 3 when one is missed), and prints a table (cloud_analysis/evaluation/report.hpp).

#include <filesystem>
#include <string>

#include <CLI/CLI.hpp>

#include "cloud_analysis/evaluation/entity_eval.hpp"
#include "cloud_analysis/evaluation/labels_2d.hpp"

namespace cloud_analysis::app {

/// Flags of `evaluate`, filled by CLI11.
struct EvaluateArgs {
    std::filesystem::path entities;    ///< --entities: entity JSON to score (cars)
    std::filesystem::path disparity;   ///< --disparity: our KITTI 16-bit disparity PNG
    std::filesystem::path kitti_root;  ///< --kitti-root: folder with calib/, instance/, ...
    std::string frame;                 ///< --frame: frame id, e.g. 000000_10
    std::filesystem::path
        gt_disparity;                   ///< --gt-disparity: overrides <root>/disp_occ_0/<frame>.png
    std::filesystem::path instance;     ///< --instance: overrides <root>/instance/<frame>.png
    std::filesystem::path calib;        ///< --calib: overrides <root>/calib/calib_cam_to_cam.txt
    std::filesystem::path json;         ///< --json: also write the scores as JSON ("-" = stdout)
    double max_range_m = 30.0;          ///< --max-range: cars farther than this are ignored, m
    int min_gt_pixels = 200;            ///< --min-gt-pixels: GT cars owed for recall
    double occluder_gap_m = 1.5;        ///< --occluder-gap: GT depth gap, m; 0 = old rule
    int fallback_max_points = 9;        ///< --fallback-max-points: 2D criterion up to this many
    std::filesystem::path reference;    ///< --reference: reference entity file (entity-to-entity)
    std::filesystem::path labels;       ///< --labels: KITTI label_2 file as the reference
    int min_visible_pixels = 0;         ///< --min-visible-pixels: fewer in --instance = not scored
    double min_visible_fraction = 0.0;  ///< --min-visible-fraction: less visible = not scored
    std::filesystem::path visibility;   ///< --visibility: overrides <root>/visibility/<frame>.json
    cloud_analysis::EntityEvalOptions entity_eval;  ///< --match-distance, --eval-range, ...
    cloud_analysis::EvalBars bars;                  ///< --require-recall, ... (exit 3)
    std::filesystem::path labels_2d;          ///< --labels-2d: 2D boxes (JSON or KITTI label_2)
    cloud_analysis::Match2dOptions match_2d;  ///< --min-iou-2d, --min-box-height, ...
    double max_false_per_frame = -1.0;        ///< --max-false-per-frame bar (2D labels)
    bool tracked_only = false;                ///< --tracked-only: things with a track_id only
};

/// Exit code of `evaluate` when the scores miss a bar (--require-recall, ...).
inline constexpr int kExitBarMissed = 3;

/// Registers `evaluate` on app and binds its flags to args (which must outlive parsing).
/// main() runs run_evaluate(args) when the returned subcommand was parsed (`if (*sub)`).
CLI::App* add_evaluate_command(CLI::App& app, EvaluateArgs& args);

/// Runs the evaluation: table to stdout (to stderr when --json is "-"), JSON to --json.
/// Throws CLI::ValidationError for inconsistent flags (map to exit 2) and std::exception
/// for failures (map to exit 1, message "<what failed>: <detail> (<file>)"). Returns 0, or
/// kExitBarMissed after printing one stderr line per missed bar.
int run_evaluate(const EvaluateArgs& args);

}  // namespace cloud_analysis::app
