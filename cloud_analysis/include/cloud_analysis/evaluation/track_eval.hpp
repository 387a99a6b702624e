#pragma once

/// Tracking evaluation of a drive: CLEAR MOT (Bernardin & Stiefelhagen 2008: MOTA, ID
/// switches, fragmentations), identity scores (Ristani et al. 2016: IDF1), HOTA (Luiten et
/// al. 2020), velocity error,
/// heading flips and the size steadiness of parked objects, per class and distance bin.
/// The truth is a synthetic drive's per-frame entity files (scene-render sensors --frames) or
/// KITTI tracking labels (label_02). See docs/evaluation.md "Tracking".

#include <array>
#include <cstdint>
#include <filesystem>
#include <map>
#include <string>
#include <string_view>
#include <vector>

#include <scene_schema/entities.hpp>

#include "cloud_analysis/evaluation/entity_eval.hpp"
#include "cloud_analysis/evaluation/hota.hpp"

namespace cloud_analysis {

/// One object of one frame, truth or hypothesis.
struct TrackedObject {
    std::int64_t track_id = 0;  ///< truth id or the tracker's track_id
    scene_schema::Entity box;   ///< class, centre, size, heading, velocity when known
    bool owed = true;           ///< truth only: false = not scored (hidden, DontCare-like)
};

/// One frame: truth and hypotheses.
struct TrackedFrame {
    std::int64_t index = 0;                 ///< frame number
    std::vector<TrackedObject> truth;       ///< ground-truth objects
    std::vector<TrackedObject> hypotheses;  ///< tracked entities (with a track_id)
};

/// Settings of evaluate_tracks.
struct TrackEvalOptions {
    double max_match_distance_m = 2.0;  ///< bird's-eye centre distance a match may have, metres
    double max_range_m = 50.0;          ///< truth farther than this (bird's eye) is not owed
    double moving_speed_mps = 0.5;      ///< truth faster than this is "moving", m/s
    /// Classes scored (others are ignored on both sides).
    std::vector<std::string> classes = {"car", "truck", "bus", "person", "rider", "bicycle"};
    /// Throws std::invalid_argument naming the bad field.
    void validate() const;
};

/// Counts of one class in one distance bin (or over all bins).
struct TrackCounts {
    std::size_t truth = 0;       ///< owed truth objects over all frames
    std::size_t hypotheses = 0;  ///< hypotheses scored (not matched to unowed truth)
    std::size_t matches = 0;     ///< true positives
    std::size_t misses = 0;      ///< false negatives
    std::size_t false_positives = 0;
    std::size_t id_switches = 0;     ///< a truth object matched to another track than before
    std::size_t fragmentations = 0;  ///< a truth track's coverage interrupted and resumed
    /// 1 - (misses + false positives + id switches) / truth (1 when there is no truth).
    double mota() const;
};

/// One scored event of a drive, for diagnosis (evaluate-tracks --events).
struct TrackEvent {
    enum class Kind { kMiss, kFalsePositive, kIdSwitch, kHeadingFlip };
    Kind kind = Kind::kMiss;
    std::int64_t frame = 0;            ///< frame number
    std::int64_t truth_id = -1;        ///< truth object (-1 for a false positive)
    std::int64_t track_id = -1;        ///< track (-1 for a miss)
    std::int64_t previous_track = -1;  ///< an ID switch's earlier track
    double range_m = 0.0;              ///< bird's-eye range of the truth (else the track)
};

/// "frame 12 id switch: truth 3 track 7 (was 4) at 18.2 m".
std::string describe(const TrackEvent& event);

/// Scores of one class.
struct ClassTrackScore {
    std::string class_name;
    /// Distance bins of entity_eval (0-10, 10-20, 20-30, 30-50), then all.
    std::array<TrackCounts, kDistanceBinEdges_m.size() + 1> bins;
    double idf1 = 1.0;  ///< 2 IDTP / (truth + hypotheses), over all bins
    /// HOTA over all bins, similarity 1 - distance / max_match_distance_m (bird's eye).
    HotaScore hota;
    std::size_t id_true_positives = 0;               ///< IDTP of the best identity matching
    std::vector<double> moving_velocity_errors_mps;  ///< |v_hyp - v_truth|, moving truth
    std::vector<double> static_velocity_errors_mps;  ///< the same for still truth
    std::size_t heading_flips = 0;  ///< consecutive outputs of a track turning > 90 degrees
    /// Largest spread (max - min over W, H, L) of a track's size while it follows a still
    /// truth object, metres (0 when none).
    double parked_size_spread_m = 0.0;
    std::vector<TrackEvent> events;  ///< every miss, false positive, ID switch and flip
};

/// Result of evaluate_tracks.
struct TrackEvaluation {
    TrackEvalOptions options;
    std::size_t frames = 0;
    std::vector<ClassTrackScore> classes;  ///< sorted by name
    /// The class's scores (throws std::out_of_range when absent).
    const ClassTrackScore& of(const std::string& class_name) const;
};

/// Scores a drive. Per frame and class, CLEAR MOT matching: a truth object keeps last frame's
/// track when it is still within max_match_distance_m, the rest are matched by the Hungarian
/// method on bird's-eye distance. Hypotheses matched to unowed truth are neither true nor
/// false positives. IDF1 matches truth and track identities once for the whole drive.
TrackEvaluation evaluate_tracks(const std::vector<TrackedFrame>& frames,
                                const TrackEvalOptions& options);

/// A frame's tracked entities as hypotheses (entities without a track_id are left out).
std::vector<TrackedObject> hypotheses_of(const scene_schema::EntityDocument& document);

/// A synthetic drive's truth frame: every entity with a track_id (the truth id); `visible`
/// (optional, by entity index) marks objects under the visibility bar as not owed.
std::vector<TrackedObject> truth_of(const scene_schema::EntityDocument& document,
                                    const std::vector<bool>& owed = {});

/// KITTI tracking labels (label_02: "frame track_id type truncated occluded alpha bbox(4)
/// h w l x y z rotation_y [score]", one object per line) grouped by frame. Classes as
/// class_of_kitti_type; DontCare and Van boxes and objects occluded >= 2 are not owed.
/// Velocities come from the positions of consecutive frames times fps (camera-relative, as
/// the entity format's velocity). Throws std::runtime_error "line N: <rule> (<origin>)".
std::map<std::int64_t, std::vector<TrackedObject>> parse_kitti_tracking_labels(
    std::string_view text, const std::string& origin, double fps);

/// Pass bars of a drive; a negative value switches a bar off.
struct TrackBars {
    std::string class_name = "car";
    double min_mota = -1.0;
    int max_id_switches = -1;
    double min_idf1 = -1.0;
    double max_median_moving_velocity_error_mps = -1.0;
    /// Largest median speed error of still objects (a parked car's track should stand still
    /// over the ground), m/s.
    double max_median_still_velocity_error_mps = -1.0;
    int max_heading_flips = -1;
    double max_parked_size_spread_m = -1.0;
    /// True when at least one bar is on.
    bool any() const;
};

/// One line per missed bar ("MOTA 0.850 < 0.900 (--min-mota)"); empty when all pass.
std::vector<std::string> check_track_bars(const TrackEvaluation& evaluation, const TrackBars& bars);

/// The report: one table row per class and distance bin, then the identity and motion scores.
std::string format_track_report(const TrackEvaluation& evaluation);

}  // namespace cloud_analysis
