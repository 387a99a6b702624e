#pragma once

/// Scores as `cloud-analysis evaluate` shows them: a table for people and a JSON document for
/// scripts, built side by side from the same numbers. See docs/evaluation.md.

#include <cstddef>
#include <optional>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>
#include <scene_schema/entities.hpp>

#include "cloud_analysis/evaluation/diagnosis.hpp"
#include "cloud_analysis/evaluation/entity_eval.hpp"
#include "cloud_analysis/evaluation/evaluate.hpp"
#include "cloud_analysis/evaluation/labels_2d.hpp"
#include "cloud_analysis/stereo/disparity.hpp"

namespace cloud_analysis {

/// A report being built: each report_* call appends its table lines and sets its JSON keys.
struct EvaluationReport {
    std::string table;                               ///< text table, lines ending in '\n'
    nlohmann::json json = nlohmann::json::object();  ///< scores by section
    std::vector<std::string> missed_bars;            ///< one line per missed pass bar
};

/// Disparity scores of `file` against its ground truth: json["disparity"] and one line.
void report_disparity(const DisparityScore& s, const std::string& file, EvaluationReport& report);

/// An entity file and the reference it is scored against, with what says which references
/// are too hidden to be owed.
struct EntityComparison {
    std::string entities_file;                    ///< the file scored
    std::string reference_file;                   ///< the reference entity or label_2 file
    std::vector<scene_schema::Entity> estimate;   ///< the scored file's entities
    std::vector<scene_schema::Entity> reference;  ///< the reference's entities
    int min_visible_pixels = 0;                   ///< fewer visible pixels: not scored; 0 = off
    std::vector<std::size_t> visible_pixels;      ///< per reference, when min_visible_pixels
    double min_visible_fraction = 0.0;            ///< less visible: not scored; 0 = off
    std::vector<std::optional<ReferenceVisibility>> visibility;  ///< per reference, when
                                                                 ///< min_visible_fraction
};

/// Entity-to-entity scores (evaluate_entities, and once more with every reference scored):
/// json["entities"] (with the reasons of diagnose_entities in "diagnosis"), json["bars"] when
/// bars.any(), the table, and the missed bars.
void report_entities(const EntityComparison& comparison, const EntityEvalOptions& options,
                     const EvalBars& bars, EvaluationReport& report);

/// Car entities of `entities_file` scored against the ground-truth cars (evaluate_cars; the 2D
/// fallback when `fallback_camera` is given): json["cars"] and the table, one row per GT car
/// in range or matched, then the reasons of diagnose_cars (with `image` and `camera`, what a
/// phantom's image box shows).
void report_cars(const std::string& entities_file,
                 const std::vector<scene_schema::Entity>& entities, const std::vector<GtCar>& gt,
                 const CarMatchOptions& options, const GtCarOptions& gt_options,
                 const StereoCamera* fallback_camera, EvaluationReport& report,
                 const InstanceImage* image = nullptr, const StereoCamera* camera = nullptr);

/// The ground plane an entity file reports (extra["ground_plane"]), when it has one:
/// json["ground_plane"] and one line.
void report_ground_plane(const scene_schema::EntityDocument& doc, EvaluationReport& report);

/// Entity files scored against 2D labels, frame by frame (score_frame_2d).
struct Labels2dComparison {
    std::string labels_file;      ///< the labels read
    std::string entities_source;  ///< entity file or folder scored
    /// Only the things a tracker confirmed (a track_id) were scored (evaluate --tracked-only).
    bool tracked_only = false;
    std::vector<FrameLabels2d> labels;                        ///< per scored frame
    std::vector<std::vector<scene_schema::Entity>> estimate;  ///< per scored frame
    std::vector<FrameScore2d> scores;                         ///< per scored frame
};

/// Pass bars of the 2D scores (off when negative).
struct Labels2dBars {
    Category2d category = Category2d::vehicle;  ///< category the bars apply to
    double require_recall = -1.0;               ///< least recall of owed labels, [0, 1]
    double max_false_per_frame = -1.0;          ///< most false entities a frame, on average
    bool any() const { return require_recall >= 0.0 || max_false_per_frame >= 0.0; }
};

/// 2D scores: json["labels_2d"] (totals per category, then each frame's false entities and
/// missed labels), the table and the missed bars.
void report_labels_2d(const Labels2dComparison& comparison, const Match2dOptions& options,
                      const Labels2dBars& bars, EvaluationReport& report);

}  // namespace cloud_analysis
