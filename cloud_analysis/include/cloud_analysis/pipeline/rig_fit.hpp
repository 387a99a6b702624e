#pragma once

/// The analysis fitted to the stereo rig of a frame: the disparity range from the nearest depth
/// to see, every pixel setting scaled from the focal length at which it is written, and frames
/// over a pixel count analysed at half resolution (docs/cli.md, "Any stereo rig").
///
/// A pixel setting of the stages after the matcher is written for KITTI's rig (focal length
/// kReferenceFocalPx); the same scene seen through a rig with focal length f spans
/// f / kReferenceFocalPx as many pixels across, so lengths in pixels scale by that factor and
/// pixel counts by its square. The matcher's settings (window, penalties, speckle filter) and
/// disparity-valued settings work on image texture and the matcher's sub-pixel error, which are
/// pixels of any camera, and stay as they are.

#include <set>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "cloud_analysis/cloud/types.hpp"
#include "cloud_analysis/entities/extract.hpp"
#include "cloud_analysis/pipeline/entity_document.hpp"
#include "cloud_analysis/pipeline/pipeline.hpp"

namespace cloud_analysis {

/// Focal length, px, at which the analysis's pixel settings are written: KITTI's rectified
/// colour cameras (P_rect_02 of the 2011_09_26 calibration).
inline constexpr double kReferenceFocalPx = 721.5377;

/// What fit_to_rig changed, for the entity file's source and the user.
struct RigFit {
    AnalyseOptions analyse;             ///< the options fitted to the rig
    ExtractOptions extract;             ///< the extraction options fitted to the rig
    double scale = 1.0;                 ///< focal length over kReferenceFocalPx (1 when off)
    bool range_from_min_depth = false;  ///< num_disparities came from rig.min_depth_m
    double nearest_depth_m = 0.0;       ///< nearest depth the disparity range reaches, metres
    std::vector<std::string> warnings;  ///< one line each: a range short of the minimum depth
    /// The entity file's source.rig block: scale, range, nearest depth, resolution.
    nlohmann::json describe(const LoadedInputs& inputs) const;
    /// The analyse options of a run: `analyse`, reprojecting straight into the extractor's
    /// per-class points (AnalyseOptions::class_points_only) when no cloud is written.
    AnalyseOptions run_options(const Palette& palette, bool clouds) const;
    /// `base` with the fitted settings and the source.rig block of `inputs`.
    RunSettings run_settings(RunSettings base, const LoadedInputs& inputs) const;
};

/// Disparity, px, of a point at `depth_m` on the optical axis (fx B / z less the principal
/// points' offset cx_right - cx, as Q reprojects it).
double disparity_at_depth(const StereoCamera& camera, double depth_m);

/// The depth, metres, of disparity `disparity_px` (infinity at or below the offset).
double depth_at_disparity(const StereoCamera& camera, double disparity_px);

/// Fits `analyse` and `extract` to the rectified rig `camera` (after any halving by
/// load_inputs), following analyse.rig:
/// - num_disparities: the nearest multiple of 16 (at least 16, at most the matcher's maximum)
///   to the full-resolution disparity at rig.min_depth_m, unless rig.given names it; a given
///   range that stops short of that depth adds a warning;
/// - pixel settings after the matcher (rig.scale_pixel_settings, rig_scaled_fields()) times
///   scale = fx / kReferenceFocalPx, pixel counts times scale^2; fields in rig.given are kept.
/// Throws std::runtime_error when the image is narrower than the range plus the window.
RigFit fit_to_rig(const AnalyseOptions& analyse, const ExtractOptions& extract,
                  const StereoCamera& camera);

/// Halves `inputs` in place (images by area averaging, label images by the top-left pixel of
/// each 2x2 block, the rig's intrinsics accordingly, an odd last column or row dropped) and
/// records it in inputs.resolution_scale.
void halve_inputs(LoadedInputs& inputs);

/// The option fields fit_to_rig may scale, by name (the flags that set them are the names with
/// '-' for '_'): a field the user gave is kept as given.
const std::set<std::string>& rig_scaled_fields();

}  // namespace cloud_analysis
