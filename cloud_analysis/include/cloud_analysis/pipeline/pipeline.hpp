#pragma once

/// The analyse chain up to the labelled cloud: load and validate every input, then
/// rectify (raw input only) -> disparity -> semantic association -> reprojection.

#include <filesystem>
#include <optional>
#include <set>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "cloud_analysis/cloud/instances.hpp"
#include "cloud_analysis/cloud/reproject.hpp"
#include "cloud_analysis/cloud/semantic.hpp"
#include "cloud_analysis/cloud/types.hpp"
#include "cloud_analysis/geometry/scene_geometry.hpp"
#include "cloud_analysis/io/io.hpp"
#include "cloud_analysis/stereo/calibration.hpp"
#include "cloud_analysis/stereo/disparity.hpp"

namespace cloud_analysis {

/// Input files of one frame.
struct InputPaths {
    std::filesystem::path left;         ///< left image
    std::filesystem::path right;        ///< right image
    std::filesystem::path semantic;     ///< semantic colour image of the left view; empty = none
    std::filesystem::path instance;     ///< instance image of the left view; empty = none
    std::filesystem::path calibration;  ///< calibration file (any supported format)
    std::string frame_id;               ///< frame id written to the entity file
};

/// KITTI layout of `root` for `frame` (e.g. "000000_10"): image_2/, image_3/, semantic_rgb/
/// (when the file exists) and calib/<frame>.txt, calib/<frame without _10>.txt or
/// calib/calib_cam_to_cam.txt, the first that exists.
InputPaths kitti_layout(const std::filesystem::path& root, const std::string& frame);

/// The instance image of `frame` in KITTI layout: instance/<frame>.png under `root`.
std::filesystem::path kitti_instance_path(const std::filesystem::path& root,
                                          const std::string& frame);

/// How the analysis fits itself to the rig of a frame (pipeline/rig_fit.hpp).
struct RigOptions {
    /// Nearest depth the disparity range must reach, metres: sets num_disparities unless given
    /// (3 m: 128 disparities on KITTI's rig); 0 = keep num_disparities as it is.
    double min_depth_m = 3.0;
    /// Frames with more pixels are analysed at half resolution (2.5 MP: a 5 MP frame is, a
    /// Cityscapes 2 MP frame is not); 0 = never. Not with raw (unrectified) input.
    long long half_resolution_above_px = 2'500'000;
    bool scale_pixel_settings = true;  ///< scale pixel settings by fx / kReferenceFocalPx
    std::set<std::string> given;       ///< option fields the user set (rig_scaled_fields(),
                                       ///< "num_disparities"): kept as they are
    /// Throws std::invalid_argument naming the first bad field.
    void validate() const;
};

/// Settings of the whole chain.
struct AnalyseOptions {
    std::string palette = "cityscapes";  ///< bundled palette name or palette file path
    CalibrationOptions calibration;      ///< KITTI camera indices
    bool raw = false;                    ///< inputs are unrectified: undistort + rectify first
    DisparityOptions disparity;          ///< SGBM and post-filters
    ReprojectOptions reproject;          ///< range limits and the depth edge band, whichever
                                         ///< path makes the classes
    /// Where the per-pixel classes come from: "labels" (the semantic image), "geometry" (the
    /// stereo pair alone, docs/stereo-only.md) or "auto" (labels when a semantic image is given).
    std::string semantics = "auto";
    /// How the instance image (InputPaths::instance) stores its objects: auto, kitti,
    /// cityscapes or colour (cloud/instances.hpp).
    std::string instance_encoding = "auto";
    geometry::GeometryOptions geometry;  ///< the stereo-only path's settings
    /// When set, analyse builds no cloud: it reprojects straight into the entity extractor's
    /// per-class points (AnalyseResult::points, see reproject_by_class), for runs whose only
    /// output is entities. Unset: the labelled cloud (AnalyseResult::cloud).
    std::optional<ClassSelection> class_points_only;
    RigOptions rig;  ///< fitting to the rig (fit_to_rig; load_inputs halves large frames)
    /// Throws std::invalid_argument naming the first bad field.
    void validate() const;
};

/// Everything read from disk, checked for consistency.
struct LoadedInputs {
    InputPaths paths;         ///< where it came from
    ImageU8 left;             ///< as read (grey or RGB)
    ImageU8 right;            ///< as read
    ImageU8 semantic;         ///< RGB, empty when no semantic image was given
    IdImage instance;         ///< as stored, empty when no instance image was given
    Calibration calibration;  ///< with camera.width/height set to the rectified image size
    Palette palette;          ///< palette of the semantic image
    /// 1, or 0.5 when load_inputs halved the frame (RigOptions::half_resolution_above_px);
    /// the images and calibration.camera are then the halved ones
    double resolution_scale = 1.0;
    int read_width_px = 0;   ///< size of the images as read
    int read_height_px = 0;  ///< idem
};

/// Reads and validates every input before any expensive work: files readable and decodable,
/// left/right/semantic/instance of one size, an instance image only with a semantic image
/// and without `raw`, calibration complete with a positive baseline, its image
/// size (when it has one) equal to the images', raw rectification data present when `raw`.
/// Then, without `raw`, a frame over options.rig.half_resolution_above_px pixels is halved
/// (halve_inputs). Throws std::runtime_error "<what failed>: <detail> (<file>)".
LoadedInputs load_inputs(const InputPaths& paths, const AnalyseOptions& options);

/// As load_inputs with a calibration and palette already read (batch mode reads them once);
/// only the images are read and every consistency check is made again.
LoadedInputs load_inputs(const InputPaths& paths, const AnalyseOptions& options,
                         const Calibration& calibration, const Palette& palette);

/// Throws std::runtime_error "image too narrow" when a rectified image `width_px` wide (0 =
/// unknown, not checked) cannot hold the range and window of `d`.
void check_range_fits(int width_px, const DisparityOptions& d);

/// Milliseconds spent in one stage.
struct StageTiming {
    std::string stage;  ///< e.g. "disparity"
    double ms = 0.0;    ///< wall time, milliseconds
};

/// Products of the chain.
struct AnalyseResult {
    StereoCamera camera;     ///< rectified rig used
    DisparityMap disparity;  ///< left disparity, px
    ClassImage classes;      ///< per-pixel classes (empty without semantic image)
    InstanceMap instances;   ///< per-pixel objects (empty without instance image); its ids
                             ///< are also in the cloud's or the points' instance_id
    std::string semantics;   ///< "labels", "geometry" or "none" (no classes)
    std::optional<geometry::SceneGeometry> geometry;  ///< stereo-only path: ground, segments,
                                                      ///< warnings (its classes moved to classes)
    LabeledCloud cloud;                ///< metric labelled points (empty with class_points_only)
    ClassPoints points;                ///< with class_points_only: the extractor's points
    std::size_t cloud_points = 0;      ///< points of the cloud, built or not
    std::vector<StageTiming> timings;  ///< per stage
};

/// Runs rectify (if raw) -> disparity -> classify -> reproject. Throws std::runtime_error when
/// the disparity has no valid pixel or no point survives reprojection.
AnalyseResult analyse(const LoadedInputs& inputs, const AnalyseOptions& options);

/// As above with a matcher kept across frames (its options replace options.disparity).
AnalyseResult analyse(const LoadedInputs& inputs, const AnalyseOptions& options,
                      DisparityMatcher& matcher);

/// Which path makes the classes of `inputs` under `options`: "labels", "geometry" or "none"
/// ("labels" asked for without a semantic image).
std::string semantics_path(const LoadedInputs& inputs, const AnalyseOptions& options);

/// What the user should know about an analysed frame, one line each: the stereo-only path's
/// warnings, no semantic image (every point void), semantic colours not in the palette (the
/// calibration's own note is Calibration::note). The single run prints them; a batch records
/// them per frame.
std::vector<std::string> analysis_warnings(const LoadedInputs& inputs, const AnalyseResult& result);

/// The `source` block of the entity file: tool, version, inputs, calibration, parameters.
nlohmann::json describe_run(const LoadedInputs& inputs, const AnalyseOptions& options,
                            const std::string& tool_version);

}  // namespace cloud_analysis
