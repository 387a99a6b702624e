#pragma once

/// Stereo calibration in three file formats, the Q reprojection matrix and rectification of raw
/// (distorted, unrectified) input. Formats are documented in docs/cli.md:
/// - KITTI raw `calib_cam_to_cam.txt` (P_rect_0x, and K/D/R_rect/S_rect for raw input);
/// - KITTI object calibration (`P2:` / `P3:` lines);
/// - the project's own flat YAML or JSON (fx, fy, cx, cy, baseline_m, optional distortion).

#include <array>
#include <filesystem>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include <Eigen/Core>

#include "cloud_analysis/cloud/types.hpp"
#include "cloud_analysis/io/io.hpp"

namespace cloud_analysis {

/// Which cameras of a KITTI calibration form the pair, and the rig's disparity offset.
struct CalibrationOptions {
    int left_camera = 2;   ///< KITTI camera index of the left image (2 = left colour)
    int right_camera = 3;  ///< KITTI camera index of the right image (3 = right colour)
    /// Added to every matched disparity before it becomes depth, px: the rig's residual
    /// principal-point difference after rectification (docs/clouds.md "Disparity offset"),
    /// applied as a shift of the right principal point. |offset| <= kMaxDisparityOffsetPx.
    double disparity_offset_px = 0.0;
    void validate() const;
};

/// The largest disparity offset a calibration takes, px.
inline constexpr double kMaxDisparityOffsetPx = 8.0;

/// One unrectified camera and the map from it to the rectified image (KITTI raw layout).
struct RawCamera {
    Eigen::Matrix3d K = Eigen::Matrix3d::Identity();       ///< intrinsics of the raw image, px
    std::vector<double> distortion;                        ///< k1 k2 p1 p2 [k3], OpenCV order
    Eigen::Matrix3d R_rect = Eigen::Matrix3d::Identity();  ///< rotation raw -> rectified
    Eigen::Matrix<double, 3, 4> P_rect = Eigen::Matrix<double, 3, 4>::Zero();  ///< projection
};

/// A calibration file, read.
struct Calibration {
    std::string format;   ///< "kitti_raw", "kitti_object", "yaml" or "json"
    std::string source;   ///< file it came from
    std::string note;     ///< how a missing value was derived (empty when none was)
    StereoCamera camera;  ///< rectified rig; width/height 0 when the file has no size
    /// t of the left camera's projection P = K [I | t] (KITTI formats): a point X0 of the
    /// rectified reference camera 0, the frame of KITTI's labels, is X0 + t in the left camera.
    /// Zero for the project's YAML/JSON (the left camera is the reference).
    Eigen::Vector3d reference_offset_m = Eigen::Vector3d::Zero();
    std::optional<RawCamera> raw_left;   ///< present when the file can rectify raw input
    std::optional<RawCamera> raw_right;  ///< idem
};

/// Parses calibration text; `origin` names the file in errors. Throws std::runtime_error
/// "cannot read calibration: <field>: <rule> (<origin>)" for a missing field or zero baseline.
Calibration parse_calibration(std::string_view text, const std::string& origin,
                              const CalibrationOptions& options = {});

/// Reads and parses a calibration file.
Calibration load_calibration(const std::filesystem::path& path,
                             const CalibrationOptions& options = {});

/// Undistorts and rectifies a raw image into the rectified grid (cv::initUndistortRectifyMap +
/// remap). The output has the rectified size of `camera` (or the input size if 0). Bilinear,
/// or nearest neighbour for label images whose colours must not blend.
ImageU8 rectify_image(const ImageU8& raw, const RawCamera& raw_camera, const StereoCamera& camera,
                      bool nearest = false);

}  // namespace cloud_analysis
