#pragma once

/// A small deterministic street scene made in code: a ray-cast ground plane 1.65 m below the
/// camera, a building wall, a back wall, cars and persons as upright boxes, all with procedural
/// texture fixed to the surfaces so that the left and right views agree. It gives stereo pairs
/// with exactly known disparity, semantics and entities for tests and the bundled sample.

#include <scene_schema/entities.hpp>

#include "cloud_analysis/cloud/types.hpp"
#include "cloud_analysis/io/io.hpp"

namespace cloud_analysis {

/// Rig and randomness of the synthetic scene.
struct SyntheticOptions {
    int width_px = 621;             ///< image width (KITTI at half resolution)
    int height_px = 188;            ///< image height
    double fx_px = 360.75;          ///< focal length, px (KITTI's 721.5 at half resolution)
    double baseline_m = 0.54;       ///< stereo baseline, m (KITTI's rig)
    double camera_height_m = 1.65;  ///< camera above the road, m (KITTI's rig)
    int supersampling = 2;          ///< rays per pixel side (anti-aliasing), 1..4
    unsigned seed = 1;              ///< texture seed
    /// Throws std::invalid_argument naming the first bad field.
    void validate() const;
};

/// Rendered views and ground truth.
struct SyntheticScene {
    StereoCamera camera;                 ///< rectified rig
    ImageU8 left;                        ///< grey left view
    ImageU8 right;                       ///< grey right view
    ImageU8 semantic;                    ///< Cityscapes colours of the left view
    DisparityMap disparity;              ///< exact left disparity (missing on sky)
    scene_schema::EntityDocument truth;  ///< the boxes and extents that were rendered
};

/// Renders the scene (deterministic for given options).
SyntheticScene make_synthetic_scene(const SyntheticOptions& options);

/// The flat YAML calibration of the scene's rig (the format load_calibration reads).
std::string synthetic_calibration_yaml(const StereoCamera& camera);

}  // namespace cloud_analysis
