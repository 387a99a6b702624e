#include "cloud_analysis/odometry/visual_odometry.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <sstream>
#include <stdexcept>

#include <Eigen/LU>
#include <opencv2/calib3d.hpp>
#include <opencv2/core.hpp>
#include <opencv2/core/eigen.hpp>
#include <opencv2/features2d.hpp>
#include <opencv2/imgproc.hpp>
#include <opencv2/video/tracking.hpp>

#include "cloud_analysis/io/mat_view.hpp"
#include "scene_schema/sequence.hpp"

namespace cloud_analysis::odometry {
namespace {

Pose pose_of(const cv::Mat& rvec, const cv::Mat& tvec) {
    cv::Mat R;
    cv::Rodrigues(rvec, R);
    Eigen::Matrix3d r;
    Eigen::Vector3d t;
    cv::cv2eigen(R, r);
    cv::cv2eigen(tvec, t);
    Pose T = Pose::Identity();
    T.topLeftCorner<3, 3>() = r;
    T.topRightCorner<3, 1>() = t;
    return T;
}

/// FAST corners (Rosten & Drummond 2006) of `grey` where `mask` is set, the strongest of each
/// square cell of corner_cell_px, about max_corners in all: spread over the image, so that the
/// motion is not fitted to one textured patch.
std::vector<cv::Point2f> spread_corners(const cv::Mat& grey, const cv::Mat& mask,
                                        const OdometryOptions& options) {
    std::vector<cv::KeyPoint> found;
    cv::FAST(grey, found, 20, true);
    const double cell = options.corner_cell_px;
    const int columns = static_cast<int>(std::ceil(grey.cols / cell));
    const int rows = static_cast<int>(std::ceil(grey.rows / cell));
    const auto per_cell = static_cast<std::size_t>(
        std::max(1, options.max_corners / std::max(1, columns * rows) + 1));
    std::vector<std::vector<cv::KeyPoint>> cells(static_cast<std::size_t>(columns * rows));
    for (const cv::KeyPoint& k : found) {
        const int u = static_cast<int>(k.pt.x), v = static_cast<int>(k.pt.y);
        if (mask.at<std::uint8_t>(v, u) == 0) continue;
        const int c = static_cast<int>(v / cell) * columns + static_cast<int>(u / cell);
        cells[static_cast<std::size_t>(c)].push_back(k);
    }
    std::vector<cv::Point2f> out;
    for (auto& c : cells) {
        const auto keep = std::min(per_cell, c.size());
        std::partial_sort(
            c.begin(), c.begin() + static_cast<std::ptrdiff_t>(keep), c.end(),
            [](const cv::KeyPoint& a, const cv::KeyPoint& b) { return a.response > b.response; });
        for (std::size_t k = 0; k < keep; ++k) out.push_back(c[k].pt);
    }
    return out;
}

}  // namespace

void OdometryOptions::validate() const {
    if (max_corners < 10) throw std::invalid_argument("max_corners: must be >= 10");
    if (!(corner_cell_px >= 4.0)) throw std::invalid_argument("corner_cell_px: must be >= 4");
    if (track_window_px < 5 || track_window_px % 2 == 0) {
        throw std::invalid_argument("track_window_px: must be odd and >= 5");
    }
    if (track_levels < 0 || track_levels > 8) {
        throw std::invalid_argument("track_levels: must be in [0, 8]");
    }
    if (!(max_round_trip_px > 0.0)) throw std::invalid_argument("max_round_trip_px: must be > 0");
    if (!(max_stereo_gap_px > 0.0)) throw std::invalid_argument("max_stereo_gap_px: must be > 0");
    if (!(max_relative_depth_error > 0.0 && max_relative_depth_error < 1.0)) {
        throw std::invalid_argument("max_relative_depth_error: must be in (0, 1)");
    }
    if (!(disparity_noise_px > 0.0)) throw std::invalid_argument("disparity_noise_px: must be > 0");
    if (!(ransac_threshold_px > 0.0)) {
        throw std::invalid_argument("ransac_threshold_px: must be > 0");
    }
    if (ransac_iterations < 10) throw std::invalid_argument("ransac_iterations: must be >= 10");
    if (min_inliers < 6) throw std::invalid_argument("min_inliers: must be >= 6");
}

/// Image pyramids of Lucas-Kanade (cv::buildOpticalFlowPyramid), kept for the next frame.
struct VisualOdometry::Pyramid {
    std::vector<cv::Mat> levels;
};

namespace {

VisualOdometry::Pyramid pyramid_of(const cv::Mat& grey, const OdometryOptions& options) {
    VisualOdometry::Pyramid p;
    cv::buildOpticalFlowPyramid(grey, p.levels,
                                cv::Size(options.track_window_px, options.track_window_px),
                                options.track_levels);
    return p;
}

/// The pixels whose corners may vote: a disparity known well enough, a static class.
cv::Mat voting_mask(const OdometryFrame& prev, double min_disparity) {
    const int w = prev.left.width_px, h = prev.left.height_px;
    const auto n = static_cast<std::size_t>(w) * static_cast<std::size_t>(h);
    cv::Mat mask(h, w, CV_8U);
    for (std::size_t p = 0; p < n; ++p) {
        const bool near = double{prev.disparity.disparity_px[p]} > min_disparity;
        const bool still = prev.static_mask.empty() || prev.static_mask[p] != 0;
        mask.data[p] = near && still ? 255 : 0;
    }
    return mask;
}

/// 3D points of the previous frame and their pixels in the current left image.
struct Correspondences {
    std::vector<cv::Point3f> object;
    std::vector<cv::Point2f> image;
};

/// The corners tracked into the current left image and back (round trip within
/// max_round_trip_px), each matched across the previous pair (its own sub-pixel disparity, near
/// the dense one), lifted to 3D with the calibration.
Correspondences track_corners(const OdometryFrame& prev, const cv::Mat& prev_grey,
                              const VisualOdometry::Pyramid& prev_pyramid,
                              const VisualOdometry::Pyramid& curr_pyramid,
                              const std::vector<cv::Point2f>& corners, const StereoCamera& camera,
                              const OdometryOptions& options, double min_disparity) {
    const int w = prev.left.width_px, h = prev.left.height_px;
    const MatchBorder border = match_border(camera);
    std::vector<cv::Point2f> forward, back;
    std::vector<std::uint8_t> ok_forward, ok_back;
    std::vector<float> error;
    const cv::Size window(options.track_window_px, options.track_window_px);
    cv::calcOpticalFlowPyrLK(prev_pyramid.levels, curr_pyramid.levels, corners, forward, ok_forward,
                             error, window, options.track_levels);
    cv::calcOpticalFlowPyrLK(curr_pyramid.levels, prev_pyramid.levels, forward, back, ok_back,
                             error, window, options.track_levels);
    // Each corner's own match in the previous right image, from the dense disparity.
    const bool stereo = !prev.right.empty();
    std::vector<cv::Point2f> across;
    std::vector<std::uint8_t> ok_across;
    if (stereo) {
        for (const cv::Point2f& c : corners) {
            const float d = prev.disparity.disparity_px[static_cast<std::size_t>(std::lround(c.y)) *
                                                            static_cast<std::size_t>(w) +
                                                        static_cast<std::size_t>(std::lround(c.x))];
            across.emplace_back(c.x - d, c.y);
        }
        cv::calcOpticalFlowPyrLK(
            prev_grey, grey_of(prev.right), corners, across, ok_across, error, window, 1,
            cv::TermCriteria(cv::TermCriteria::COUNT | cv::TermCriteria::EPS, 30, 0.01),
            cv::OPTFLOW_USE_INITIAL_FLOW);
    }
    Correspondences out;
    for (std::size_t k = 0; k < corners.size(); ++k) {
        if (!ok_forward[k] || !ok_back[k]) continue;
        if (cv::norm(back[k] - corners[k]) > options.max_round_trip_px) continue;
        const cv::Point2f& f = forward[k];
        if (f.x < 0.0f || f.y < 0.0f || f.x > static_cast<float>(w - 1) ||
            f.y > static_cast<float>(h - 1)) {
            continue;
        }
        const int u = static_cast<int>(std::lround(corners[k].x));
        const int v = static_cast<int>(std::lround(corners[k].y));
        float d =
            prev.disparity.disparity_px[static_cast<std::size_t>(v) * static_cast<std::size_t>(w) +
                                        static_cast<std::size_t>(u)];
        if (stereo) {
            const float own = corners[k].x - across[k].x;
            if (!ok_across[k] ||
                double{std::abs(across[k].y - corners[k].y)} > options.max_stereo_gap_px ||
                double{std::abs(own - d)} > options.max_stereo_gap_px) {
                continue;
            }
            d = own;
        }
        if (!(double{d} > min_disparity)) continue;
        const double z = border.depth_m(double{d});
        out.object.emplace_back(
            static_cast<float>((double{corners[k].x} - camera.cx_px) * z / camera.fx_px),
            static_cast<float>((double{corners[k].y} - camera.cy_px) * z / camera.fy_px),
            static_cast<float>(z));
        out.image.push_back(f);
    }
    return out;
}

/// The motion of the correspondences: RANSAC over P3P, then Levenberg-Marquardt on the inliers.
void solve_motion(const Correspondences& c, const StereoCamera& camera,
                  const OdometryOptions& options, MotionEstimate& out) {
    const std::vector<cv::Point3f>& object = c.object;
    const std::vector<cv::Point2f>& image = c.image;
    const cv::Matx33d K(camera.fx_px, 0.0, camera.cx_px, 0.0, camera.fy_px, camera.cy_px, 0.0, 0.0,
                        1.0);
    cv::Mat rvec, tvec;
    std::vector<int> inliers;
    const bool found = cv::solvePnPRansac(
        object, image, K, cv::noArray(), rvec, tvec, false, options.ransac_iterations,
        static_cast<float>(options.ransac_threshold_px), 0.999, inliers, cv::SOLVEPNP_P3P);
    out.inliers = static_cast<int>(inliers.size());
    if (!found || out.inliers < options.min_inliers) return;
    std::vector<cv::Point3f> in_object;
    std::vector<cv::Point2f> in_image;
    for (int k : inliers) {
        in_object.push_back(object[static_cast<std::size_t>(k)]);
        in_image.push_back(image[static_cast<std::size_t>(k)]);
    }
    cv::solvePnPRefineLM(in_object, in_image, K, cv::noArray(), rvec, tvec);
    out.T_curr_prev = pose_of(rvec, tvec);
    out.valid = out.T_curr_prev.allFinite();
}

/// estimate_motion with the two left images' pyramids built.
MotionEstimate motion(const OdometryFrame& prev, const VisualOdometry::Pyramid& prev_pyramid,
                      const ImageU8& curr_left, const VisualOdometry::Pyramid& curr_pyramid,
                      const StereoCamera& camera, const OdometryOptions& options) {
    const int w = prev.left.width_px, h = prev.left.height_px;
    if (curr_left.width_px != w || curr_left.height_px != h || prev.disparity.width_px != w ||
        prev.disparity.height_px != h) {
        throw std::invalid_argument("estimate_motion: images and disparity differ in size");
    }
    const auto n = static_cast<std::size_t>(w) * static_cast<std::size_t>(h);
    if (!prev.static_mask.empty() && prev.static_mask.size() != n) {
        throw std::invalid_argument("estimate_motion: static mask differs in size");
    }
    // Corners only where a point can vote: a disparity known well enough, a static class.
    const double min_disparity = options.disparity_noise_px / options.max_relative_depth_error +
                                 match_border(camera).offset_px;
    const cv::Mat prev_grey = grey_of(prev.left);
    const std::vector<cv::Point2f> corners =
        spread_corners(prev_grey, voting_mask(prev, min_disparity), options);
    MotionEstimate out;
    if (corners.size() < static_cast<std::size_t>(options.min_inliers)) return out;
    const Correspondences c = track_corners(prev, prev_grey, prev_pyramid, curr_pyramid, corners,
                                            camera, options, min_disparity);
    out.tracked = static_cast<int>(c.object.size());
    if (out.tracked < options.min_inliers) return out;
    solve_motion(c, camera, options, out);
    return out;
}

}  // namespace

MotionEstimate estimate_motion(const OdometryFrame& prev, const ImageU8& curr_left,
                               const StereoCamera& camera, const OdometryOptions& options) {
    options.validate();
    return motion(prev, pyramid_of(grey_of(prev.left), options), curr_left,
                  pyramid_of(grey_of(curr_left), options), camera, options);
}

std::vector<std::uint8_t> static_mask(const std::vector<std::uint16_t>& class_index,
                                      const std::vector<char>& is_thing) {
    std::vector<std::uint8_t> out(class_index.size(), 1);
    for (std::size_t p = 0; p < class_index.size(); ++p) {
        const std::uint16_t k = class_index[p];
        if (k < is_thing.size() && is_thing[k]) out[p] = 0;
    }
    return out;
}

VisualOdometry::VisualOdometry(const StereoCamera& camera, const OdometryOptions& options)
    : camera_(camera), options_(options) {
    options_.validate();
}

VisualOdometry::~VisualOdometry() = default;

Pose VisualOdometry::add(OdometryFrame frame) {
    // Grey once: the left image is tracked from twice (into this frame and the next).
    const auto to_grey = [](ImageU8& image) {
        if (image.channels == 1 || image.empty()) return;
        const cv::Mat grey = grey_of(image);
        image = ImageU8{image.width_px, image.height_px, 1,
                        std::vector<std::uint8_t>(grey.data, grey.data + grey.total())};
    };
    to_grey(frame.left);
    to_grey(frame.right);
    auto pyramid = std::make_unique<Pyramid>(pyramid_of(grey_of(frame.left), options_));
    if (prev_) {
        last_ = motion(*prev_, *prev_pyramid_, frame.left, *pyramid, camera_, options_);
        if (last_.valid) velocity_ = last_.T_curr_prev;
        T_world_prev_ = T_world_prev_ * velocity_.inverse();
    }
    prev_ = std::move(frame);
    prev_pyramid_ = std::move(pyramid);
    return T_world_prev_;
}

std::array<double, 12> row_major(const Pose& T) {
    std::array<double, 12> a{};
    for (std::size_t k = 0; k < 12; ++k) a[k] = T(static_cast<int>(k / 4), static_cast<int>(k % 4));
    return a;
}

std::string format_kitti_poses(const std::vector<Pose>& poses) {
    std::vector<std::array<double, 12>> rows;
    rows.reserve(poses.size());
    for (const Pose& T : poses) rows.push_back(row_major(T));
    return scene_schema::format_kitti_poses(rows);
}

std::vector<Pose> parse_kitti_poses(std::string_view text, const std::string& origin) {
    std::vector<Pose> poses;
    std::istringstream lines{std::string(text)};
    std::string line;
    for (int number = 1; std::getline(lines, line); ++number) {
        if (line.find_first_not_of(" \t\r") == std::string::npos) continue;
        std::istringstream values(line);
        Pose T = Pose::Identity();
        int count = 0;
        for (double v; values >> v; ++count) {
            if (count < 12) T(count / 4, count % 4) = v;
        }
        const std::string at = origin + ", line " + std::to_string(number);
        if (!values.eof()) throw std::runtime_error(at + ": not a number");
        if (count != 12) {
            throw std::runtime_error(at + ": expected 12 numbers (a 3x4 pose), got " +
                                     std::to_string(count));
        }
        if (!T.allFinite()) throw std::runtime_error(at + ": not finite");
        poses.push_back(T);
    }
    if (poses.empty()) throw std::runtime_error(origin + ": no poses");
    return poses;
}

}  // namespace cloud_analysis::odometry
