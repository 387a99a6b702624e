#pragma once

/// Scoring car entities against KITTI ground truth: GT cars are the instance image's car
/// instances (labelId = v >> 8 == 26, instance = v & 0xff) with their GT disparity pixels
/// reprojected to 3D; a car entity matches a GT car when its bird's-eye footprint, grown by a
/// margin, holds at least half of the car's points and is at most a maximum area.

#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>

#include <Eigen/Core>
#include <scene_schema/entities.hpp>

#include "cloud_analysis/types.hpp"

namespace cloud_analysis {

/// One ground-truth car: its instance id and the 3D points of its GT disparity pixels.
struct GtCar {
    int instance = 0;                         ///< instance id within the frame
    std::vector<Eigen::Vector3f> points_m;    ///< reprojected GT points, camera frame, metres
    std::size_t pixel_count = 0;              ///< GT disparity pixels (== points_m.size())
    int image_width_px = 0;                   ///< width of the instance image
    std::vector<std::uint32_t> image_pixels;  ///< v * width + u of its instance pixels, sorted
    Eigen::Vector3d centroid_m = Eigen::Vector3d::Zero();  ///< mean of the points
    /// Bird's-eye distance of the centroid from the camera, metres.
    double range_m() const;
};

/// Matching rule settings (issue 3 item 8).
struct CarMatchOptions {
    std::string car_class = "car";        ///< entity class name scored
    double footprint_margin_m = 0.3;      ///< footprint grown by this on every side, metres
    double min_inside_fraction = 0.5;     ///< share of the GT car's points inside, (0, 1]
    double max_footprint_area_m2 = 20.0;  ///< larger (grown) footprints never match, m^2
    double max_range_m = 30.0;            ///< only cars / entities nearer than this count
    std::size_t min_gt_pixels = 200;      ///< GT cars with fewer pixels are not owed (recall)
    /// Throws std::invalid_argument naming the bad field.
    void validate() const;
};

/// One accepted match.
struct CarMatch {
    std::size_t entity = 0;          ///< index into the entity list
    std::size_t gt = 0;              ///< index into the GT car list
    double inside_fraction = 0.0;    ///< share of the GT car's points inside the footprint
    double centre_distance_m = 0.0;  ///< bird's-eye distance entity centre to GT centroid
};

/// Result of evaluate_cars.
struct CarEvaluation {
    std::size_t gt_owed = 0;              ///< GT cars in range with >= min_gt_pixels
    std::size_t gt_owed_matched = 0;      ///< of those, matched
    std::size_t entities_in_range = 0;    ///< car entities in range
    std::size_t entities_matched = 0;     ///< of those, matched to any GT car
    std::size_t entities_unscorable = 0;  ///< unmatched ones whose centre projects onto a GT
                                          ///< car without GT disparity (not in precision)
    std::vector<CarMatch> matches;        ///< one-to-one matches (greedy by inside fraction)
    double recall() const;                ///< gt_owed_matched / gt_owed (1 when none owed)
    double precision() const;             ///< entities_matched / entities_in_range (1 when none)
    /// entities_matched / (entities_in_range - entities_unscorable) (1 when none)
    double precision_scorable() const;
    double mean_centre_distance_m() const;  ///< over matches (0 when none)
};

/// Share of points whose (x, z) lies inside the entity's footprint grown by margin_m.
double footprint_inside_fraction(const scene_schema::Entity& entity,
                                 const std::vector<Eigen::Vector3f>& points_m, double margin_m);

/// Scores car entities against GT cars (one-to-one, greedy by inside fraction). With a camera,
/// unmatched entities whose centre projects onto the pixels of a GT car that has no GT
/// disparity (the matching rule cannot judge them) are counted as unscorable.
CarEvaluation evaluate_cars(const std::vector<scene_schema::Entity>& entities,
                            const std::vector<GtCar>& gt_cars, const CarMatchOptions& options,
                            const StereoCamera* camera = nullptr);

/// GT cars from a KITTI instance PNG (uint16) and a GT disparity PNG (uint16, d * 256, 0 =
/// none) of the same size, including cars without any GT disparity (no points); throws
/// std::runtime_error naming the file.
std::vector<GtCar> load_gt_cars(const std::filesystem::path& instance_png,
                                const std::filesystem::path& disparity_png,
                                const StereoCamera& camera, int car_label_id = 26);

/// A labelled cloud from a KITTI GT disparity PNG and a semantic colour image (for tuning
/// and tests without SGBM); throws std::runtime_error naming the file.
LabeledCloud cloud_from_gt_disparity(const std::filesystem::path& disparity_png,
                                     const std::filesystem::path& semantic_png,
                                     const Palette& palette, const StereoCamera& camera);

}  // namespace cloud_analysis
