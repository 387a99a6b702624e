#pragma once

/// Scoring car entities against KITTI ground truth: GT cars are the instance image's car
/// instances (labelId = v >> 8 == 26, instance = v & 0xff) with their GT disparity pixels
/// reprojected to 3D, minus the pixels of occluders that the mask bleeds over; a car entity
/// matches a GT car when its bird's-eye footprint, grown by a margin, holds at least half of
/// the car's points and is at most a maximum area. GT cars with (almost) no GT points are
/// matched by KITTI's 2D criterion instead. See docs/evaluation.md "Cars".

#include <cstdint>
#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include <Eigen/Core>
#include <scene_schema/entities.hpp>

#include "cloud_analysis/cloud/types.hpp"

namespace cloud_analysis {

/// One ground-truth car: its instance id, its mask and the 3D points of its own surface.
struct GtCar {
    int instance = 0;                         ///< instance id within the frame
    std::vector<Eigen::Vector3f> points_m;    ///< GT points of its own surface, camera frame, m
    std::size_t pixel_count = 0;              ///< GT disparity pixels kept (== points_m.size())
    std::size_t occluder_pixel_count = 0;     ///< GT disparity pixels dropped as occluders
    int image_width_px = 0;                   ///< width of the instance image
    int image_height_px = 0;                  ///< height of the instance image
    std::vector<std::uint32_t> image_pixels;  ///< v * width + u of its instance pixels, sorted
    Eigen::Vector4d mask_box_px = Eigen::Vector4d::Zero();  ///< mask rectangle, pixel edges
    Eigen::Vector3d centroid_m = Eigen::Vector3d::Zero();   ///< mean of the points
    /// Bird's-eye distance of the centroid from the camera, metres.
    double range_m() const;
};

/// Settings of the car matching rule (docs/evaluation.md "Cars").
struct CarMatchOptions {
    std::string car_class = "car";        ///< entity class name scored
    double footprint_margin_m = 0.3;      ///< footprint grown by this on every side, metres
    double min_inside_fraction = 0.5;     ///< share of the GT car's points inside, (0, 1]
    double max_footprint_area_m2 = 20.0;  ///< larger (grown) footprints never match, m^2
    double max_range_m = 30.0;            ///< only cars / entities nearer than this count
    std::size_t min_gt_pixels = 200;      ///< GT cars with fewer pixels are not owed (recall)
    std::size_t fallback_max_points = 9;  ///< GT cars with at most this many points are matched
                                          ///< by the 2D criterion (needs a camera)
    double fallback_min_iou = 0.5;        ///< 2D criterion: least IoU of projected box and mask
                                          ///< rectangle, (0, 1]
    /// Throws std::invalid_argument naming the bad field.
    void validate() const;
};

/// One accepted match.
struct CarMatch {
    std::size_t entity = 0;          ///< index into the entity list
    std::size_t gt = 0;              ///< index into the GT car list
    double inside_fraction = 0.0;    ///< share of the GT car's points inside the footprint
    double centre_distance_m = 0.0;  ///< bird's-eye distance entity centre to GT centroid
    bool fallback = false;           ///< matched by the 2D criterion (GT car without points)
    double iou_2d = 0.0;             ///< 2D criterion: IoU of projected box and mask rectangle
};

/// Result of evaluate_cars.
struct CarEvaluation {
    std::size_t gt_owed = 0;              ///< GT cars in range with >= min_gt_pixels
    std::size_t gt_owed_matched = 0;      ///< of those, matched
    std::size_t entities_in_range = 0;    ///< car entities in range
    std::size_t entities_matched = 0;     ///< of those, matched to any GT car
    std::size_t entities_unscorable = 0;  ///< unmatched ones whose centre projects onto a GT
                                          ///< car without GT points (not in precision)
    std::size_t fallback_matched = 0;     ///< of entities_matched, by the 2D criterion
    std::vector<CarMatch> matches;        ///< one-to-one matches (footprint rule first, greedy)
    double recall() const;                ///< gt_owed_matched / gt_owed (1 when none owed)
    double precision() const;             ///< entities_matched / entities_in_range (1 when none)
    /// entities_matched / (entities_in_range - entities_unscorable) (1 when none)
    double precision_scorable() const;
    double mean_centre_distance_m() const;  ///< over matches (0 when none)
};

/// Share of points whose (x, z) lies inside the entity's footprint grown by margin_m.
double footprint_inside_fraction(const scene_schema::Entity& entity,
                                 const std::vector<Eigen::Vector3f>& points_m, double margin_m);

/// Image rectangles are (u0, v0, u1, v1) in pixel-edge coordinates: pixel (u, v) covers
/// [u, u + 1) x [v, v + 1), so a mask spanning columns 3..5 is u0 = 3, u1 = 6.
///
/// The image rectangle of an entity's 3D box: its 8 corners projected with the camera (pixel
/// centres at integer u, v) and clipped to a width x height image; nullopt when a corner is
/// not in front of the camera (z < 0.1 m) or the box lies outside the image.
std::optional<Eigen::Vector4d> projected_box_px(const scene_schema::Entity& entity,
                                                const StereoCamera& camera, int width_px,
                                                int height_px);

/// IoU of two image rectangles (u0, v0, u1, v1), in [0, 1] (0 when both are empty).
double rect_iou(const Eigen::Vector4d& a, const Eigen::Vector4d& b);

/// Scores car entities against GT cars, one-to-one: first pairs that meet the footprint rule
/// (greedy by inside fraction), then, with a camera, pairs of an entity and a GT car with at
/// most fallback_max_points points whose projected 3D box and mask rectangle overlap with
/// IoU >= fallback_min_iou and whose grown footprint is within the area limit (KITTI's 2D
/// criterion, greedy by IoU). Unmatched entities whose centre projects onto such a car are
/// counted as unscorable.
CarEvaluation evaluate_cars(const std::vector<scene_schema::Entity>& entities,
                            const std::vector<GtCar>& gt_cars, const CarMatchOptions& options,
                            const StereoCamera* camera = nullptr);

/// How GT cars are read from the instance and disparity images.
struct GtCarOptions {
    int car_label_id = 26;        ///< Cityscapes labelId of cars in the instance image
    double occluder_gap_m = 1.5;  ///< depth gap that splits a car's GT depths into groups,
                                  ///< metres; 0 = keep every point (the mask as given)
    int min_interior_px = 3;      ///< a GT pixel this far (chessboard) inside its mask's
                                  ///< border with other labels is interior, pixels, >= 1
    /// Throws std::invalid_argument naming the bad field.
    void validate() const;
};

/// One GT point of a car for own_surface_min_depth_m.
struct GtDepth {
    float z_m = 0.0f;       ///< depth, metres
    bool interior = false;  ///< at least min_interior_px inside the car's mask
};

/// The nearest depth of a car's own surface among its GT points (any order). The depths are
/// split at gaps larger than occluder_gap_m; the car's own surface is the group with the most
/// interior points (the largest group when no point is interior): a mask that bleeds over an
/// occluder or the background does so in a thin strip along its border, while the car's own
/// surface fills its interior. Nearer points belong to occluders (occluders are in front).
/// Returns 0 for an empty list or when occluder_gap_m is 0 (keep everything).
float own_surface_min_depth_m(std::vector<GtDepth> points, const GtCarOptions& options);

/// Chessboard distance of every pixel of a w x h label image to the nearest pixel of another
/// label (8-neighbour chamfer, exact for the chessboard metric); pixels next to another label
/// get 1. The image border is not a label border. Row-major, like `labels`.
std::vector<int> label_border_distance_px(const std::vector<std::uint16_t>& labels, int width_px,
                                          int height_px);

/// GT cars from a KITTI instance PNG (uint16) and a GT disparity PNG (uint16, d * 256, 0 =
/// none) of the same size, including cars without any GT disparity (no points); points nearer
/// than own_surface_min_depth_m are dropped as occluders. Throws std::runtime_error naming the
/// file.
std::vector<GtCar> load_gt_cars(const std::filesystem::path& instance_png,
                                const std::filesystem::path& disparity_png,
                                const StereoCamera& camera, const GtCarOptions& options = {});

/// A labelled cloud from a KITTI GT disparity PNG and a semantic colour image (for tuning
/// and tests without SGBM); throws std::runtime_error naming the file.
LabeledCloud cloud_from_gt_disparity(const std::filesystem::path& disparity_png,
                                     const std::filesystem::path& semantic_png,
                                     const Palette& palette, const StereoCamera& camera);

}  // namespace cloud_analysis
