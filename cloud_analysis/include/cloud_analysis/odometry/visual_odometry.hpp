#pragma once

/// Stereo visual odometry: where the left camera went between consecutive frames of a drive.
/// Corners of the previous left image (FAST, Rosten & Drummond 2006, spread over a grid) are
/// tracked into the current one (pyramidal
/// Lucas-Kanade, kept when the backward track returns within a pixel) and matched across the
/// previous pair (Lucas-Kanade along the row from the dense disparity: a corner's own sub-pixel
/// disparity, where a matching window centred on an outline would mix two depths), lifted to
/// 3D, and the motion is the robust 3D-2D fit of those points to
/// their tracked pixels (RANSAC over P3P, then Levenberg-Marquardt on the inliers), as in
/// libviso2 (Geiger, Ziegler, Stiller, "StereoScan", IV 2011) without its own matcher. Pixels of
/// thing classes (cars, people: what may move) do not vote. A drive also estimates the rig's
/// disparity offset from the motion's parallax (self-calibration of the principal points'
/// difference, as in Dang, Hoffmann, Stiller, IEEE TIP 2009). See docs/odometry.md.

#include <array>
#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include <Eigen/Core>

#include "cloud_analysis/cloud/types.hpp"
#include "cloud_analysis/io/io.hpp"

namespace cloud_analysis::odometry {

/// A rigid transform as a 4x4 matrix: T_a_b maps points of frame b into frame a.
using Pose = Eigen::Matrix4d;

/// Settings of the odometry.
struct OdometryOptions {
    int max_corners = 1000;        ///< corners kept in the previous image, >= 10
    double corner_cell_px = 32.0;  ///< corners are kept strongest first per square cell of this
                                   ///< side, the same number in each: spread over the image, px,
                                   ///< >= 4
    int track_window_px = 7;       ///< Lucas-Kanade window side, px, odd, >= 5
    int track_levels = 3;          ///< image pyramid levels above the image, [0, 8]
    /// Levels climbed when the tracks start where the last motion puts the corners (a drive's
    /// frames after its first motion): the change of motion between two frames moves a
    /// corner by a few pixels, which one level above the image covers, [0, 8].
    int predicted_track_levels = 1;
    double max_round_trip_px = 1.0;  ///< forward-backward track error kept, px, > 0
    double max_stereo_gap_px = 1.0;  ///< a corner's match across the pair: off its row, or
                                     ///< off the dense disparity, by at most this, px, > 0
    /// A point votes when its depth is known to this share at least: its disparity at least
    /// disparity_noise_px / max_relative_depth_error (5 px, 78 m on KITTI's rig). Far points pin
    /// the rotation (their image motion is mostly the turn); their depth error, growing as z^2,
    /// weighs little in the reprojection fit, and the rig's disparity offset is estimated
    /// (disparity_offset_prior_px), (0, 1).
    double max_relative_depth_error = 0.1;
    double disparity_noise_px = 0.5;   ///< the disparity's error at a corner, px, > 0
    double ransac_threshold_px = 1.0;  ///< reprojection error of an inlier, px, > 0
    int ransac_iterations = 300;       ///< RANSAC hypotheses, >= 10
    int min_inliers = 12;              ///< fewer: the motion is not trusted (previous motion
                                       ///< kept), >= 6
    /// The rig's disparity offset (added to every measured disparity: a rectification error
    /// between the two principal points, which makes far points too far) is estimated from
    /// the motion: each frame pair's parallax gives it with a variance, and the drive's
    /// estimate is their information-weighted mean. Its prior: mean 0, this deviation, px, > 0.
    double disparity_offset_prior_px = 1.0;
    bool estimate_disparity_offset = true;  ///< false: the disparities are taken as they are
    /// Throws std::invalid_argument naming the bad field.
    void validate() const;
};

/// What one frame gives the odometry.
struct OdometryFrame {
    ImageU8 left;            ///< rectified left image (grey or RGB)
    ImageU8 right;           ///< rectified right image; empty: the dense disparity alone
    DisparityMap disparity;  ///< the left image's disparity, px
    /// Per pixel, 1 where a point may vote (static scene), 0 on things that may move; empty:
    /// every pixel votes.
    std::vector<std::uint8_t> static_mask;
};

/// The motion between two frames.
struct MotionEstimate {
    Pose T_curr_prev = Pose::Identity();  ///< previous camera frame -> current camera frame
    int tracked = 0;                      ///< corners tracked both ways with a depth
    int inliers = 0;                      ///< of them, agreeing with the motion
    bool valid = false;                   ///< at least min_inliers inliers
    double disparity_offset_px = 0.0;     ///< the offset the points were lifted with
};

/// The motion of the left camera from `prev` to `curr` (images of one size, `camera` their
/// rectified rig), the disparities corrected by the rig's disparity_offset_px (see
/// OdometryOptions::disparity_offset_prior_px; VisualOdometry estimates it).
MotionEstimate estimate_motion(const OdometryFrame& prev, const ImageU8& curr_left,
                               const StereoCamera& camera, const OdometryOptions& options,
                               double disparity_offset_px = 0.0);

/// `image` in grey (OpenCV's RGB to grey, as the odometry reads it), converted straight into
/// the result; a copy when it is grey already. A frame given in grey is not converted again.
ImageU8 grey_image(const ImageU8& image);

/// The per-pixel vote mask of a class image: 0 on the palette's thing classes, 1 elsewhere.
std::vector<std::uint8_t> static_mask(const std::vector<std::uint16_t>& class_index,
                                      const std::vector<char>& is_thing);

/// Chains the motions of a drive's frames into poses T_world_camera, the world being the first
/// frame's left camera (KITTI odometry's convention). A frame whose motion is not trusted
/// moves as the one before it did (constant velocity). After a trusted motion the next frame's
/// tracks start where that motion puts the corners (OdometryOptions::predicted_track_levels);
/// when fewer than half as many inliers agree, they are tracked again from scratch.
class VisualOdometry {
  public:
    VisualOdometry(const StereoCamera& camera, const OdometryOptions& options);
    ~VisualOdometry();
    VisualOdometry(VisualOdometry&&) noexcept = default;
    VisualOdometry& operator=(VisualOdometry&&) noexcept = default;
    /// Adds the next frame; returns its pose.
    Pose add(OdometryFrame frame);
    /// The last motion's estimate (invalid for the first frame).
    const MotionEstimate& last_motion() const { return last_; }
    /// The drive's disparity offset estimate so far, px (0 before any motion).
    double disparity_offset_px() const { return offset_.mean_px; }

    struct Pyramid;  ///< the previous left image's image pyramid (behind the .cpp: OpenCV)

  private:
    StereoCamera camera_;
    OdometryOptions options_;
    std::optional<OdometryFrame> prev_;
    Pose T_world_prev_ = Pose::Identity();
    Pose velocity_ = Pose::Identity();  ///< the last trusted T_curr_prev
    MotionEstimate last_;
    std::unique_ptr<Pyramid> prev_pyramid_;
    /// The disparity offset as a Gaussian in information form (a constant of the rig).
    struct Offset {
        double mean_px = 0.0;
        double information = 0.0;  ///< 1 / variance, px^-2
    } offset_;
};

/// KITTI odometry poses text: per frame one line of the 3x4 matrix [R | t] of T_world_camera,
/// row-major, 12 numbers.
std::string format_kitti_poses(const std::vector<Pose>& poses);

/// The row-major 3x4 [R | t] of a pose (frame.pose).
std::array<double, 12> row_major(const Pose& T);

/// Parses that text; throws std::runtime_error "<origin>, line N: <reason>".
std::vector<Pose> parse_kitti_poses(std::string_view text, const std::string& origin);

}  // namespace cloud_analysis::odometry
