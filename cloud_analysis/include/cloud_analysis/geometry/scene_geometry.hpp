#pragma once

/// Scene understanding from the stereo pair alone: the road plane fitted without labels, the
/// obstacles standing on it segmented in u-disparity space (Labayrade et al., "Real Time
/// Obstacle Detection in Stereovision on Non Flat Road Geometry Through V-disparity
/// Representation", IV 2002; Badino et al., "The Stixel World", DAGM 2009, for cutting each
/// column into ground / object / sky), classified by rules on their metric shape, the vehicles
/// among them decided by random trees trained on rendered streets (segment_classifier.hpp),
/// written as a per-pixel class image in the palette's classes so that the labelled extractor
/// runs on it unchanged. See docs/stereo-only.md.

#include <cstdint>
#include <limits>
#include <memory>
#include <string>
#include <vector>

#include "cloud_analysis/cloud/semantic.hpp"
#include "cloud_analysis/cloud/types.hpp"
#include "cloud_analysis/entities/ground.hpp"
#include "cloud_analysis/io/io.hpp"

namespace cloud_analysis::geometry {

class SegmentClassifier;

/// Entities made from classes the geometry decided carry this share of the confidence the
/// labelled path gives the same support (docs/entities.md, "Confidence").
inline constexpr double kConfidenceScale = 0.6;

/// Settings of derive_semantics.
struct GeometryOptions {
    double ground_max_range_m = 35.0;      ///< only pixels nearer than this vote for the road, m
    double ground_inlier_m = 0.08;         ///< RANSAC inlier distance of the road plane, metres
    double ground_tolerance_m = 0.12;      ///< pixels this close to the plane are road (at 0 m), m
    double disparity_noise_px = 1.0;       ///< disparity error the road tolerance grows with, px
    double min_camera_height_m = 0.3;      ///< a plane nearer the camera than this is no road, m
    double max_camera_height_m = 4.0;      ///< a plane farther below the camera is no road, m
    double max_depth_m = 60.0;             ///< obstacle pixels beyond this stay unlabelled, m
    double max_obstacle_height_m = 6.0;    ///< heights above this count as this, metres
    std::string segmentation = "columns";  ///< obstacles split into segments by "columns"
                                           ///< (u-disparity cells linked column band to band,
                                           ///< tall and low apart) or "clusters" (the same cells
                                           ///< grouped by 3D Euclidean clustering; compared in
                                           ///< docs/entities.md)
    double cluster_distance_m = 0.5;       ///< "clusters": distance at 10 m, growing with depth, m
    int column_bin_px = 4;                 ///< u-disparity cell width, pixels, >= 1
    double disparity_bin_share = 0.04;     ///< u-disparity bins are 1 px or this share of the
                                           ///< disparity wide, whichever is wider, (0, 1)
    double link_depth_m = 0.8;             ///< cells closer in depth than this join, metres
    int min_cell_pixels = 3;               ///< sparser u-disparity cells are noise, pixels, >= 1
    double min_cell_height_m = 0.2;        ///< ... and so are cells holding fewer pixels than a
                                           ///< surface this tall across the cell would, metres
    double top_behind_px = 0.25;           ///< a cell's top is its pixels' at most this much
                                           ///< disparity behind the cell's mean (a bus's side
                                           ///< above a car's roof shares the car's bin at range,
                                           ///< 1-2 px farther), px, > 0
    double foot_ahead_px = 0.5;            ///< ... and, unless the cell has no other, not a
                                           ///< pixel more than this ahead of the cell's mean
                                           ///< whose column runs on up into the upper layer
                                           ///< (blend_rows rows, steps under blend_step_px):
                                           ///< the lowest edge of a crown a metre before a
                                           ///< car's end shares its bin at range, px, > 0
    double behind_gap_m = 2.0;             ///< a lower cell farther than this beyond the
                                           ///< segment's nearest lower cell in its column band
                                           ///< is a surface seen above or beside the nearer
                                           ///< thing (a bus's back beyond a row's last car):
                                           ///< its top is not the segment's, while such cells
                                           ///< are fewer than the rest, metres, >= 0, 0 = off
    double split_surface_px = 0.5;         ///< a lower cell whose mean disparity lies within
                                           ///< this of a dense, tall, not green lower cell one
                                           ///< disparity bin away in its column band is that
                                           ///< surface, split over two bins at their border (a
                                           ///< bus's back 1 m beyond a car at 30 m): tall when
                                           ///< its heights lie within that cell's, and its
                                           ///< pixels at those heights give its top only when
                                           ///< it has no other, px, >= 0, 0 = off
    int blend_rows = 4;                    ///< ... and not a pixel whose column is nearer this
    double blend_step_px = 0.3;            ///< many rows above and farther as far below, each by
                                           ///< more than this (the matcher's blend of a crown
                                           ///< and the bus's side behind it, in a car's bins),
                                           ///< unless the cell has no other; rows >= 1, px >= 0
    double low_cut_m = 0.35;               ///< pixels lower than this above the road take their
                                           ///< cell's class, or sidewalk/terrain alone, metres
    double layer_height_m = 2.3;           ///< cells hold the pixels below and above this height in
                                           ///< two layers: cars below, crowns and walls' upper
                                           ///< floors above, metres
    double continuity_band_m = 0.3;        ///< a surface continues across layer_height_m (a
                                           ///< wall, a trunk: its cells are tall) when it fills
    double continuity_share = 0.3;         ///< this share of the band this tall on both sides of
                                           ///< it; else the layers stay apart, metres, (0, 1]
    double continuity_behind_m = 0.5;      ///< a lower cell's pixels in that band count only
    double continuity_behind_px = 0.35;    ///< when at most this far behind its mean depth or
                                           ///< mean disparity (the bus's back over a car's roof
                                           ///< shares the car's bin at 30 m, 0.4 px farther),
                                           ///< metres >= 0 (0 = every pixel counts), px > 0
    double car_min_height_m = 0.9;         ///< car tops lie between this ...
    double car_max_height_m = 2.2;         ///< ... and this above the road (below layer_height_m:
                                           ///< a segment reaching it meets a surface above), m
    double car_min_width_m = 1.2;          ///< narrower objects are persons or poles, metres
    /// A car's length, metres: a segment of the rules' car class that the classifier rejects
    /// and that spans one and a half of these or more is cut into pieces about this long, each
    /// judged again (a row of parked vehicles that stereo sees as one surface).
    double vehicle_piece_m = 4.5;
    /// A vehicle's body below its waist stands upright; a surface whose depth grows with its
    /// height by more than this (metres per metre; 3: a slope of 1 in 3, 18 degrees, the
    /// flattest usual embankment) beyond twice its standard error (Segment::lean) is a bank, a
    /// verge or a hedge's sloping foot, not a car. 0 = off.
    double car_max_lean = 3.0;
    double car_min_edge_share = 0.28;      ///< a car's back and sides are bands of horizontal
                                           ///< edges (bumper, sills, window line, roof): at
                                           ///< least this share of its pixels' grey-level
                                           ///< gradient energy points within 20 degrees of
                                           ///< vertical. An isotropic texture (grass, leaves,
                                           ///< a porous hedge) holds 0.22, upright posts and
                                           ///< trunks less; [0, 1), 0 = off. A segment falling
                                           ///< short keeps as car the column bands where a
                                           ///< window ...
    double edge_window_m = 1.2;            ///< ... this wide at its depth reaches it, metres > 0
    int edge_step_px = 1;                  ///< edges are read on the grey image averaged over
                                           ///< boxes this wide (the detail a 3x3 Sobel sees at
                                           ///< KITTI's focal length), px, >= 1
    double building_min_height_m = 2.6;    ///< taller objects are buildings (or trees), metres
    double wall_top_spread_m = 0.2;        ///< a segment whose tops (25th-97th percentile) vary
                                           ///< less than this is no car: one upright face (a
                                           ///< car's cells, at the depths of its bumper, sides,
                                           ///< windows and roof, vary by 0.25 m or more), m
    double wall_top_spread_near_m = 0.35;  ///< ... the same nearer than wall_near_depth_m, where
                                           ///< a car's parts fall in cells of their own (0.43 m
                                           ///< or more on the rendered scenes), metres
    double wall_near_depth_m = 25.0;       ///< ... the depth that holds within, metres
    double wall_max_thickness_m = 0.8;     ///< ... a wall or fence when its footprint is thinner
                                           ///< than this, else static (kerbside clutter), metres
    double wall_min_width_m = 2.2;         ///< ... when longer than this (a car's back, its boot
                                           ///< seen alone, is as flat and thin but narrower), m
    double pole_max_width_m = 0.6;         ///< tall objects narrower than this are poles, metres
    double low_max_height_m = 0.6;         ///< objects lower than this are kerbs or low plants, m
    double green_fraction = 0.45;          ///< objects with more green pixels are vegetation, (0,1]
    int green_window_px = 2;               ///< a pixel is green when the mean colour of the window
                                           ///< this far around it is (leaves' shadows), px, >= 0
    double min_face_share = 0.15;          ///< a thing entity seen over less than this share of
                                           ///< its smallest prior face (W x H) is a fragment or
                                           ///< clutter and is dropped, [0, 1), 0 = off
    int threads = 2;                       ///< threads of the per-pixel passes, >= 1
    /// Decides which segments are vehicles (segment_classifier.hpp); null: the rules do.
    std::shared_ptr<const SegmentClassifier> classifier;
    /// Decides which of the segments that are no vehicle are persons; null: the rules do.
    std::shared_ptr<const SegmentClassifier> person_classifier;
    /// Throws std::invalid_argument naming the bad field.
    void validate() const;
};

/// The road plane found without labels and what it implies about the camera.
struct GroundEstimate {
    bool found = false;            ///< a plausible road plane was found
    GroundPlane plane;             ///< the plane (camera frame), valid when found
    double camera_height_m = 0.0;  ///< camera centre above the plane, metres
    double pitch_deg = 0.0;        ///< camera pitch against the road (positive: looks down), deg
    double roll_deg = 0.0;         ///< camera roll against the road, degrees
    double horizon_v_px = 0.0;     ///< image row of the horizon at the principal column, px
    std::string problem;           ///< why no road was accepted, empty when found
};

/// One obstacle segment, what the rules measured of it and the class they gave it.
struct Segment {
    std::uint16_t class_index = kVoidClass;  ///< palette class, kVoidClass when unmapped
    std::string label;                       ///< rule's class name, e.g. "car"
    std::size_t pixels = 0;                  ///< obstacle pixels
    std::size_t cells = 0;                   ///< u-disparity cells
    double top_m = 0.0;                      ///< robust top above the road (97 % of its own
                                             ///< cells' tops, behind_gap_m), metres
    double top_q25_m = 0.0;                  ///< 25 % of its cells' tops, metres
    double low_m = 0.0;                      ///< 10 % of its cells' lowest heights, metres
    double width_m = 0.0;                    ///< footprint extent along its main axis, metres
    double thickness_m = 0.0;                ///< footprint extent across it, metres
    double depth_m = 0.0;                    ///< median distance of its cells, metres
    double near_m = 0.0;                     ///< 5 % of its cells' distances, metres
    double far_m = 0.0;                      ///< 95 % of its cells' distances, metres
    double green = 0.0;                      ///< share of green pixels, [0, 1]
    double occluded = 0.0;                   ///< share of pixels whose top a nearer surface hides
    double horizontal_edges = -1.0;          ///< share of its pixels' gradient energy in
                                             ///< horizontal edges (car_min_edge_share), -1
                                             ///< without a left image
    bool tall = false;                       ///< most pixels in cells of a surface reaching
                                             ///< above layer_height_m
    /// Car candidates: how far the surface of its lower body (0.25-0.65 m above the road) leans
    /// away from the camera, metres of depth per metre of height (0: vertical), and the standard
    /// error of that; NaN when not measured.
    double lean = std::numeric_limits<double>::quiet_NaN();
    double lean_error = std::numeric_limits<double>::quiet_NaN();
    int u0 = 0, v0 = 0, u1 = -1, v1 = -1;  ///< image box of its pixels (inclusive), px
    // What the classifier reads beside the rules' measurements (measure_appearance): colour
    // from the left image (neutral without colour), surface from the disparity.
    double chroma_r = 1.0 / 3, chroma_g = 1.0 / 3,
           chroma_b = 1.0 / 3;      ///< mean of each
                                    ///< pixel's r/(r+g+b) etc.: hue and saturation
    double fill = 0.0;              ///< share of its image box its pixels fill, [0, 1]
    double luma = 0.0;              ///< mean grey level, 0..255
    double luma_cv = 0.0;           ///< grey level's standard deviation / (mean + 5)
    double grad = 0.0;              ///< mean |grey step| between neighbours in a row /
                                    ///< (mean + 5): texture
    double rough_h = 0.0;           ///< share of its neighbours in a row, and ...
    double rough_v = 0.0;           ///< ... in a column, whose disparities differ by more
                                    ///< than 0.3 px: a porous or broken surface
    double disparity_spread = 0.0;  ///< (90th - 10th percentile) / median of its disparity
    std::string rules_label;        ///< the class the rules gave it (label: the final one)
    std::vector<float> features;    ///< what the classifier reads (segment_features())
    /// Share of the classifier's trees calling it a vehicle; NaN without a classifier.
    double vehicle_votes = std::numeric_limits<double>::quiet_NaN();
    /// Share of the person classifier's trees calling it a person; NaN when not asked (no
    /// person classifier, or a vehicle).
    double person_votes = std::numeric_limits<double>::quiet_NaN();
};

/// What the geometry decided.
struct SceneGeometry {
    ClassImage classes;                          ///< per-pixel palette class (void where undecided)
    GroundEstimate ground;                       ///< the road plane
    std::vector<Segment> segments;               ///< obstacles, largest first
    std::vector<std::int32_t> segment_of_pixel;  ///< per pixel (v * width + u): index into
                                                 ///< segments, -1 for none
    std::vector<std::string> warnings;           ///< one line each, for the user
};

/// Derives a class image from a disparity map and its rig: road (plane within a depth-aware
/// tolerance), sky (no disparity or beyond max_depth_m above the horizon), and obstacles
/// classed car, person, pole, vegetation, building, sidewalk/terrain (low) or static.
/// Class names missing from `palette` stay void. `left` (grey or RGB, same size) gives the
/// green share; grey images give none. No road: only sky is labelled and a warning says why.
SceneGeometry derive_semantics(const DisparityMap& disparity, const StereoCamera& camera,
                               const ImageU8& left, const Palette& palette,
                               const GeometryOptions& options);

/// The road plane alone (RANSAC over the lower image's points, fit_ground_plane).
GroundEstimate estimate_ground(const DisparityMap& disparity, const StereoCamera& camera,
                               const GeometryOptions& options);

/// The segments of `g` as a JSON document (frame id, the road plane, one object per segment in
/// the order of SceneGeometry::segments: the rules' class, their measurements, the image box),
/// for `--segments-out` (docs/stereo-only.md, "Segments").
std::string segments_json(const SceneGeometry& g, const std::string& frame_id);

/// Per pixel, the index + 1 of its segment (0: none; indices above 65533 share the last
/// value), for `--segment-ids-out`; all 0 when `g` has no per-pixel segments.
ImageU16 segment_ids(const SceneGeometry& g, int width_px, int height_px);

/// RGB image of a class image in the palette's colours (void black).
ImageU8 colour_classes(const ClassImage& classes, const Palette& palette);

/// Pixel accuracy and per-class IoU of a class image against a reference class image.
struct SemanticScore {
    std::size_t pixels = 0;  ///< reference pixels scored (not void in the reference)
    double accuracy = 0.0;   ///< share of them with the same class
    std::vector<std::pair<std::string, double>> iou;  ///< per requested class, -1 when absent
};

/// Scores `estimate` against `reference` (same size, same palette) on `class_names`.
SemanticScore score_semantics(const ClassImage& estimate, const ClassImage& reference,
                              const Palette& palette, const std::vector<std::string>& class_names);

}  // namespace cloud_analysis::geometry
