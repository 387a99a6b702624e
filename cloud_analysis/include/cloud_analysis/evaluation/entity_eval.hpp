#pragma once

/// Entity-to-entity evaluation: our entities against a reference entity file (a rendered
/// scene's truth, or KITTI label_2 read by kitti_labels.hpp). Per class: greedy one-to-one
/// matching by bird's-eye centre distance, precision and recall, centre, size and heading
/// errors, bird's-eye-view and 3D IoU of oriented upright boxes, by distance bin; plus the
/// pass bars of the closed loop. See docs/evaluation.md "Closed loop".

#include <array>
#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include <Eigen/Core>
#include <scene_schema/entities.hpp>

#include "cloud_analysis/support/select.hpp"

namespace cloud_analysis {

/// Corners of an entity's footprint in the bird's-eye (x, z) plane, counter-clockwise in
/// (x, z); the heading (length axis) is (cos theta, -sin theta).
std::array<Eigen::Vector2d, 4> footprint_corners(const scene_schema::Entity& box);

/// Area of the intersection of two convex polygons given counter-clockwise (Sutherland-Hodgman
/// clipping, shoelace area), square units.
double convex_intersection_area(const std::vector<Eigen::Vector2d>& a,
                                const std::vector<Eigen::Vector2d>& b);

/// Bird's-eye-view IoU of two oriented footprints (exact rectangle intersection), in [0, 1].
double bev_iou(const scene_schema::Entity& a, const scene_schema::Entity& b);

/// 3D IoU of two upright oriented boxes: footprint intersection times overlap in y, in [0, 1].
double iou_3d(const scene_schema::Entity& a, const scene_schema::Entity& b);

/// Heading error modulo pi (a box is symmetric under a half turn), radians in [0, pi/2].
double heading_error_rad(double theta_a, double theta_b);

/// Bird's-eye distance of an entity's centre from the camera, hypot(x, z), metres.
double bev_range_m(const scene_schema::Entity& box);

/// Upper edges of the distance bins, metres: 0-10, 10-20, 20-30, 30-50.
inline constexpr std::array<double, 4> kDistanceBinEdges_m = {10.0, 20.0, 30.0, 50.0};

/// Index of the distance bin of a range (0..3), or -1 beyond the last edge.
int distance_bin(double range_m);

/// Name of bin i ("0-10", ..., "30-50"); i == kDistanceBinEdges_m.size() gives "all".
std::string distance_bin_name(int bin);

/// Settings of evaluate_entities.
struct EntityEvalOptions {
    double max_match_distance_m = 2.0;  ///< bird's-eye centre distance a match may have, metres
    double max_range_m = 50.0;          ///< entities farther than this (bird's-eye) are ignored
    double iou_threshold = 0.5;         ///< BEV IoU a match must reach to count as "good", (0,1]
    double stuff_overlap = 0.5;         ///< a stuff entity whose footprint lies at least this
                                        ///< share inside a reference thing is "stuff on a
                                        ///< thing", (0, 1]
    /// Classes scored as objects (Cityscapes things); every other class is stuff.
    std::vector<std::string> thing_classes = {"person",  "rider",  "car",        "truck",
                                              "bus",     "train",  "motorcycle", "bicycle",
                                              "caravan", "trailer"};
    /// Throws std::invalid_argument naming the bad field.
    void validate() const;
    /// True when `class_name` is in thing_classes.
    bool is_thing(const std::string& class_name) const;
};

/// One accepted match of a reference entity with an estimated one (same class).
struct EntityMatch {
    std::size_t reference = 0;        ///< index into the reference list
    std::size_t estimate = 0;         ///< index into the estimate list
    double centre_error_m = 0.0;      ///< 3D distance of the box centres, metres
    double bev_centre_error_m = 0.0;  ///< bird's-eye distance of the centres, metres
    Eigen::Vector3d size_error_m = Eigen::Vector3d::Zero();  ///< estimate - reference W, H, L
    double heading_error_rad = 0.0;                          ///< modulo pi, [0, pi/2]
    double bev_iou = 0.0;                                    ///< bird's-eye IoU
    double iou_3d = 0.0;                                     ///< 3D IoU
};

/// Scores of one class in one distance bin (or over all bins).
struct ClassBinScore {
    std::size_t reference = 0;  ///< reference entities (binned by the reference's range)
    std::size_t estimate = 0;   ///< estimates (matched: binned by their reference; else own)
    std::size_t matched = 0;    ///< matched pairs
    std::size_t missed = 0;     ///< unmatched reference entities
    std::size_t spurious = 0;   ///< unmatched estimates (things) / stuff on a thing (stuff)
    std::size_t good_iou = 0;   ///< matches with BEV IoU >= iou_threshold
    std::vector<double> centre_errors_m;         ///< per match, metres
    std::vector<double> heading_errors_deg;      ///< per match, degrees
    std::vector<double> bev_ious;                ///< per match
    std::vector<double> ious_3d;                 ///< per match
    std::vector<Eigen::Vector3d> size_errors_m;  ///< per match, estimate - reference W, H, L
    double recall() const;                       ///< matched / reference (1 when no reference)
    double precision() const;                    ///< matched / (matched + spurious) (1 when none)
    /// Share of the reference entities matched with BEV IoU >= threshold (1 when none).
    double good_iou_fraction() const;
};

/// Scores of one class: bins 0..3 and "all" (index 4, every entity within max_range_m).
struct ClassScore {
    std::string class_name;  ///< e.g. "car"
    bool thing = true;       ///< scored as objects (else only stuff-on-thing is counted)
    std::array<ClassBinScore, kDistanceBinEdges_m.size() + 1> bins;  ///< per bin, then all
};

/// Result of evaluate_entities.
struct EntityEvaluation {
    EntityEvalOptions options;          ///< settings used
    std::vector<ClassScore> classes;    ///< sorted by name; things and the stuff that offended
    std::vector<EntityMatch> matches;   ///< every accepted match
    std::vector<std::size_t> spurious;  ///< estimate indices: unmatched things, stuff on things
    std::vector<std::size_t> missed;    ///< reference indices of unmatched things in range
    std::vector<std::size_t> ignored;   ///< reference indices not scored (reference_ignored)
    /// The class's scores for a range limit: bins whose upper edge <= max_range_m merged
    /// (max_range_m must be a bin edge, e.g. 30 -> 0-10, 10-20, 20-30).
    ClassBinScore within(const std::string& class_name, double max_range_m) const;
    /// Stuff entities within max_range_m that sit on a reference thing.
    std::size_t stuff_on_things(double max_range_m) const;
};

/// Scores `estimate` against `reference`: per thing class, candidate pairs of the same class
/// with bird's-eye centre distance <= max_match_distance_m are matched greedily by ascending
/// distance, one-to-one; unmatched estimates are spurious. A stuff-class estimate whose
/// footprint lies at least stuff_overlap inside any reference thing's footprint is spurious
/// too ("an entity made out of a stuff class where a thing is"). References flagged in
/// `reference_ignored` (empty = none) take part in matching, so an estimate on them is not
/// spurious, but are not scored (like KITTI's DontCare), e.g. cars hidden behind others.
EntityEvaluation evaluate_entities(const std::vector<scene_schema::Entity>& reference,
                                   const std::vector<scene_schema::Entity>& estimate,
                                   const EntityEvalOptions& options,
                                   const std::vector<bool>& reference_ignored = {});

/// Visible pixels of each reference entity in a KITTI instance PNG (uint16, labelId << 8 | n)
/// rendered from the same file by `scene-render sensors`, whose n is the entity's 1-based
/// ordinal among the file's entities of its class_id (document order); 0 for classes without
/// instances. Throws std::runtime_error naming the file.
std::vector<std::size_t> visible_instance_pixels(
    const std::filesystem::path& instance_png, const std::vector<scene_schema::Entity>& reference);

/// How much of a reference thing the camera sees, from `scene-render sensors`'
/// visibility/<frame>.json (docs/sensors.md "Visibility").
struct ReferenceVisibility {
    std::size_t visible_px = 0;     ///< pixels in the instance image
    std::size_t unoccluded_px = 0;  ///< pixels when rendered alone (no occluders)
    double in_view_fraction = 1.0;  ///< share of it inside the image (1 - KITTI's truncation)
    double visible_fraction = 0.0;  ///< in_view_fraction * visible_px / unoccluded_px: hidden
                                    ///< or cut by the image border; 0 when not in the image
};

/// The visibility record of each reference entity, matched by id, from a visibility JSON file
/// written for the same reference file; nullopt for classes that are not things. Throws
/// std::runtime_error naming the file when it cannot be read or lacks a thing of `reference`.
std::vector<std::optional<ReferenceVisibility>> load_reference_visibility(
    const std::filesystem::path& visibility_json,
    const std::vector<scene_schema::Entity>& reference, const EntityEvalOptions& options);

/// Pass bars of the closed loop; a negative value switches a bar off.
struct EvalBars {
    std::string class_name = "car";              ///< class the bars apply to
    double max_range_m = 30.0;                   ///< bars use bins up to this edge, metres
    double require_recall = -1.0;                ///< minimum recall, [0, 1]
    int max_spurious = -1;                       ///< most unmatched estimates of the class
    int max_stuff_on_things = -1;                ///< most stuff entities sitting on things
    double max_median_centre_error_m = -1.0;     ///< metres
    double max_median_heading_error_deg = -1.0;  ///< degrees
    double min_good_iou_fraction = -1.0;         ///< share of references with BEV IoU >= thr
    /// Throws std::invalid_argument naming the bad field.
    void validate() const;
    /// True when at least one bar is on.
    bool any() const;
};

/// One line per missed bar ("recall 0.667 < 1.000 (--require-recall)"); empty when all pass.
std::vector<std::string> check_bars(const EntityEvaluation& evaluation, const EvalBars& bars);

}  // namespace cloud_analysis
