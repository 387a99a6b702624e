#pragma once

/// Cloud -> entities: the thesis's one-per-class extractors ("centroid", "average",
/// "variance") and the default "instances" extractor (ground plane, per-class clustering,
/// oriented prior-completed boxes for things, oriented extents for stuff). See docs/entities.md.

#include <string>
#include <vector>

#include <scene_schema/entities.hpp>

#include "cloud_analysis/cloud/reproject.hpp"
#include "cloud_analysis/cloud/types.hpp"
#include "cloud_analysis/entities/class_config.hpp"
#include "cloud_analysis/entities/ground.hpp"

namespace cloud_analysis {

/// Settings of extract_entities.
struct ExtractOptions {
    std::string method = "instances";  ///< "instances" | "centroid" | "average" | "variance"
    /// How a row of things parked end to end is cut: "partition" (one optimisation over the row:
    /// docs/entities.md) or "rules" (the older cascade: valleys, then walks of the prior pitch).
    std::string row_model = "partition";
    ClassConfig classes;                   ///< per-class settings (load_class_config)
    GroundOptions ground;                  ///< RANSAC settings of the ground plane
    std::string clustering = "euclidean";  ///< things: "euclidean" (3D, hash grid) or "image"
                                           ///< (pixel components refined by depth)
    int image_radius_px = 2;               ///< "image": pixel neighbourhood linked, >= 1
    double max_range_m = 60.0;             ///< points farther than this (z) are ignored, metres
    std::vector<std::string> ground_classes = {"road", "sidewalk", "parking"};  ///< plane votes
    double near_trim_fraction = 0.03;       ///< a thing's box trims this fraction of its points
                                            ///< at the end nearer the camera of an axis along
                                            ///< the viewing ray (BoxFitOptions), [0, 0.2)
    bool area_weighted_extents = true;      ///< a thing's final box takes its footprint
                                            ///< quantiles over seen surface, not points
                                            ///< (BoxFitOptions::area_weighted_extents)
    double outlier_margin_m = 0.5;          ///< thing points farther than near + prior diagonal +
                                            ///< this (bird's-eye range) are stereo smear, metres
    double shadow_fraction = 0.5;           ///< a thing cluster with more of its pixels than this
                                            ///< inside a nearer same-class cluster's row extents
                                            ///< (fragments: next to them) is a wrong-match shadow,
                                            ///< (0, 1]
    int shadow_radius_px = 10;              ///< margin of those extents, columns (and, for
                                            ///< fragments, rows above and below), pixels, >= 0
    double fragment_height_fraction = 0.3;  ///< a thing cluster whose points span less than
                                            ///< this * prior_H_m vertically (or with fewer than
                                            ///< min_points, a row piece) is a fragment, [0, 1]
    double min_width_px = 0.0;              ///< a thing with a prior narrower than this in the
                                            ///< image (median pixels per row) is a strip of
                                            ///< label bleed or edge smear, pixels, >= 0, 0 = off
                                            ///< (8 also drops far cars of small images)
    double strip_beside_width_px = 8.0;     ///< a thing narrower than this in the image lying
                                            ///< along a larger thing of its class (within
                                            ///< shadow_radius_px of it on its rows) at another
                                            ///< range is that thing's outline at another object's
                                            ///< depth (bleed, smear) and is dropped, pixels,
                                            ///< >= 0, 0 = off
    double strip_beside_gap_m = 1.0;        ///< that other range: at least this far, metres, >= 0
    double min_height_fraction = 0.3;       ///< things lower than this * prior_H_m above the ground
                                            ///< are mislabelled ground, [0, 1)
    double family_min_height_m = 0.0;  ///< things of family_class whose top lies lower than this
                                       ///< above the ground are none (the stereo-only path sets
                                       ///< its car rule's car_min_height_m), metres, >= 0, 0 = off
    double min_face_share = 0.0;       ///< things seen over less than this share of their smallest
                                       ///< prior face (W x H) are dropped, each point covering
                                       ///< (z / fx_px) (z / fy_px) square metres at its own depth z
                                       ///< (a fragment of a roof or a row, smear, clutter), [0, 1),
                                       ///< 0 = off (or without fx_px, fy_px)
    double fx_px = 0.0;                ///< the camera's focal lengths for min_face_share, px
    double fy_px = 0.0;
    /// Things: the extractor takes the pixels on every point_lattice_px-th column of every
    /// point_lattice_px-th row (1, 2, 4 or 8), each point standing for that cell's pixels. A
    /// rig with a focal length several times KITTI's sees an object in several times more
    /// pixels each way than the box fits need (fit_to_rig sets it).
    int point_lattice_px = 1;
    double row_low_fraction = 0.7;    ///< a thing blob at least two prior widths long whose top
                                      ///< stays below this * its highest top for row_low_extent_m
                                      ///< across it from the camera's side (bonnets) is a row side
                                      ///< by side seen front-on, [0, 1), 0 = off
    double row_low_extent_m = 0.6;    ///< that low extent, metres, > 0
    double row_gap_m = 0.6;           ///< gap between things in a row: pitch = prior W + this
                                      ///< side by side, prior L + this end to end, metres, >= 0
    double row_valley_depth_m = 0.4;  ///< a thing blob longer than
                                      ///< row_valley_min_length_fraction * prior_L_m is cut
                                      ///< where its top profile along its length drops this
                                      ///< far below the tops on both sides (the ends of two
                                      ///< things parked end to end between their roofs),
                                      ///< metres, >= 0, 0 = off
    double row_valley_min_length_fraction = 1.1;  ///< that length, times prior_L_m, > 0
    double row_valley_min_peak_fraction = 0.7;    ///< both tops reach this * prior_H_m, [0, 2]
    double row_valley_min_piece_m = 1.0;  ///< no cut closer than this to an end or another cut,
                                          ///< metres, > 0
    double row_valley_bin_m = 0.15;       ///< bin of the top profile along the length, metres,
                                          ///< [0.01, 10]
    double row_valley_closing_m = 0.3;    ///< dips of the top profile narrower than twice
                                          ///< this are noise (each bin takes the highest top
                                          ///< within this), metres, [0, 10]
    std::string family_class = "car";     ///< class whose boxes get a size family (car / van) in
                                          ///< the entity's `subclass`, "" = none
    double van_min_height_m = 1.82;       ///< a box of that class at least this tall is a van
                                          ///< (cars 1.4-1.5 m, SUVs 1.7 m, vans 1.9-2.1 m), metres
    double van_prior_L_m = 5.2;           ///< a van's length prior (completes what is hidden), m
    double van_prior_W_m = 2.0;           ///< a van's width prior, metres
    double van_max_L_m = 6.0;  ///< a van box longer than this holds the end of the thing before
                               ///< it too: it keeps its far end and the van prior's length, m
    double far_column_length_fraction = 1.25;  ///< a box of that class takes the far end of
                                               ///< its side from its outermost pixel column
                                               ///< (far_end_to_columns), to at most
                                               ///< this * its prior length (car or van),
                                               ///< [1, 3], 0 = off
    double stuff_on_thing_fraction = 0.5;      ///< a stuff entity with more than this share of its
                                               ///< footprint inside thing boxes is dropped (stuff
                                               ///< smeared onto a thing's silhouette), (0, 1],
                                               ///< 1 = off
    /// Threads: the classes and a thing class's clusters are shared among this many (and a
    /// cloud's split by class among as many chunks); the result does not depend on it, >= 1
    int threads = 2;
    /// Throws std::invalid_argument naming the bad field.
    void validate() const;
};

/// The seen area (square metres) under which a thing of class `s` is too faint to be one:
/// `min_face_share` of its smallest prior face; 0 when the rule is off (no prior, no share, or
/// no focal lengths).
double min_seen_area_m2(const ClassSettings& s, const ExtractOptions& options);

/// The seen area (square metres) of a thing's points `members` as the extractor takes them:
/// each covers (z / fx_px) (z / fy_px) at its own depth times its lattice cell
/// (point_lattice_px pixels each way).
double thing_seen_area_m2(const std::vector<Eigen::Vector3f>& pts,
                          const std::vector<std::size_t>& members, const ExtractOptions& options);

/// Which points of each palette class the extractor takes: stuff on every column_step-th pixel
/// column, pixels for things, depth within options.max_range_m.
ClassSelection class_selection(const Palette& palette, const ExtractOptions& options);

/// A labelled cloud split by class with `selection` (on up to `threads` threads; the result
/// does not depend on it). Columns are thinned only when the cloud has its pixels.
ClassPoints points_by_class(const LabeledCloud& cloud, const ClassSelection& selection,
                            int threads = 2);

/// Builds the entities of a labelled cloud's points split by class (points_by_class, or
/// reproject_by_class without a cloud; either with class_selection(palette, options)): ids
/// "<class>-<n>", point_count and confidence on each; sky and void never. The caller fills
/// frame and source. With method "instances" the ground plane, when found, is reported in
/// document.extra["ground_plane"] (normal, d, camera_height_m, inliers). The result passes
/// scene_schema::check() once the caller has set frame.id.
scene_schema::EntityDocument extract_entities(const ClassPoints& points, const Palette& palette,
                                              const ExtractOptions& options);

/// The same from the labelled cloud: extract_entities(points_by_class(cloud, ...), ...).
/// Image-space steps use the cloud's pixel indices; `camera` (when its focal length and
/// baseline are set) gives the matcher's left border at each depth to a cloud that does not
/// carry it (LabeledCloud::border).
scene_schema::EntityDocument extract_entities(const LabeledCloud& cloud, const Palette& palette,
                                              const StereoCamera& camera,
                                              const ExtractOptions& options);

}  // namespace cloud_analysis
