#include "cloud_analysis/odometry/visual_odometry.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <optional>
#include <sstream>
#include <stdexcept>

#include <Eigen/Cholesky>
#include <Eigen/Geometry>
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

/// FAST corners (Rosten & Drummond 2006) of `grey` where `votes(u, v)`, the strongest of each
/// square cell of corner_cell_px, about max_corners in all: spread over the image, so that the
/// motion is not fitted to one textured patch.
template <typename Votes>
std::vector<cv::Point2f> spread_corners(const cv::Mat& grey, const Votes& votes,
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
        if (!votes(u, v)) continue;
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
    if (predicted_track_levels < 0 || predicted_track_levels > 8) {
        throw std::invalid_argument("predicted_track_levels: must be in [0, 8]");
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
    if (!(disparity_offset_prior_px > 0.0)) {
        throw std::invalid_argument("disparity_offset_prior_px: must be > 0");
    }
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

/// Whether a corner at pixel (u, v) of `frame` may vote: a disparity known well enough, a
/// static class.
bool votes(const OdometryFrame& frame, int u, int v, double min_disparity) {
    const std::size_t p =
        static_cast<std::size_t>(v) * static_cast<std::size_t>(frame.left.width_px) +
        static_cast<std::size_t>(u);
    return double{frame.disparity.disparity_px[p]} > min_disparity &&
           (frame.static_mask.empty() || frame.static_mask[p] != 0);
}

/// Corners of the previous left image with their disparity, and their pixels in the current
/// left image.
struct Correspondences {
    std::vector<cv::Point2f> corner;
    std::vector<double> disparity_px;  ///< as measured, before the rig's offset
    std::vector<cv::Point2f> image;
};

/// The corner of disparity d lifted to 3D with the calibration, d corrected by offset_px.
Eigen::Vector3d lifted(const cv::Point2f& corner, double disparity_px, const StereoCamera& camera,
                       double offset_px) {
    return camera_point(camera, double{corner.x}, double{corner.y},
                        match_border(camera).depth_m(disparity_px + offset_px));
}

std::vector<cv::Point3f> object_points(const Correspondences& c, const StereoCamera& camera,
                                       double offset_px) {
    std::vector<cv::Point3f> out;
    out.reserve(c.corner.size());
    for (std::size_t k = 0; k < c.corner.size(); ++k) {
        const Eigen::Vector3d p = lifted(c.corner[k], c.disparity_px[k], camera, offset_px);
        out.emplace_back(static_cast<float>(p.x()), static_cast<float>(p.y()),
                         static_cast<float>(p.z()));
    }
    return out;
}

/// Corners of a frame's left image with their own disparity: the points a motion is fitted to.
struct Landmarks {
    std::vector<cv::Point2f> corner;
    std::vector<double> disparity_px;  ///< as measured, before the rig's offset
};

/// The lowest disparity a point votes with (OdometryOptions::max_relative_depth_error).
double min_voting_disparity(const StereoCamera& camera, const OdometryOptions& options) {
    return options.disparity_noise_px / options.max_relative_depth_error +
           match_border(camera).offset_px;
}

/// The corners of `frame` where a point can vote (a disparity known well enough, a static class),
/// each matched across the pair: its own sub-pixel disparity by Lucas-Kanade along the row from
/// the dense one, kept within max_stereo_gap_px of its row and of the dense disparity. `pyramid`:
/// the frame's left image's (its derivatives are reused).
Landmarks landmarks_of(const OdometryFrame& frame, const VisualOdometry::Pyramid& pyramid,
                       const StereoCamera& camera, const OdometryOptions& options) {
    const int w = frame.left.width_px;
    const double min_disparity = min_voting_disparity(camera, options);
    const std::vector<cv::Point2f> corners = spread_corners(
        pyramid.levels.front(), [&](int u, int v) { return votes(frame, u, v, min_disparity); },
        options);
    const auto dense = [&](const cv::Point2f& c) {
        return frame.disparity
            .disparity_px[static_cast<std::size_t>(std::lround(c.y)) * static_cast<std::size_t>(w) +
                          static_cast<std::size_t>(std::lround(c.x))];
    };
    const bool stereo = !frame.right.empty();
    std::vector<cv::Point2f> across;
    std::vector<std::uint8_t> ok_across;
    std::vector<float> error;
    if (stereo && !corners.empty()) {
        for (const cv::Point2f& c : corners) across.emplace_back(c.x - dense(c), c.y);
        const cv::Size window(options.track_window_px, options.track_window_px);
        cv::calcOpticalFlowPyrLK(
            pyramid.levels, grey_of(frame.right), corners, across, ok_across, error, window,
            std::min(1, options.track_levels),
            cv::TermCriteria(cv::TermCriteria::COUNT | cv::TermCriteria::EPS, 30, 0.01),
            cv::OPTFLOW_USE_INITIAL_FLOW);
    }
    Landmarks out;
    for (std::size_t k = 0; k < corners.size(); ++k) {
        float d = dense(corners[k]);
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
        out.corner.push_back(corners[k]);
        out.disparity_px.push_back(double{d});
    }
    return out;
}

/// `points` of pyramid `from` tracked into pyramid `to` by pyramidal Lucas-Kanade; `ok` says
/// which came back within max_round_trip_px of where they started and stay inside the image.
/// `guess` (empty, or one pixel a point): where the previous motion puts each point; the
/// tracks then start there and climb only predicted_track_levels levels, and each backward
/// track starts where the guess's displacement, undone, takes its forward track.
std::vector<cv::Point2f> tracked(const VisualOdometry::Pyramid& from,
                                 const VisualOdometry::Pyramid& to,
                                 const std::vector<cv::Point2f>& points,
                                 const std::vector<cv::Point2f>& guess, int w, int h,
                                 const OdometryOptions& options, std::vector<char>& ok) {
    ok.assign(points.size(), 0);
    std::vector<cv::Point2f> forward = guess, back;
    if (points.empty()) return forward;
    const bool guessed = !guess.empty();
    const int levels = guessed ? std::min(options.predicted_track_levels, options.track_levels)
                               : options.track_levels;
    const int flags = guessed ? cv::OPTFLOW_USE_INITIAL_FLOW : 0;
    const cv::TermCriteria stop(cv::TermCriteria::COUNT | cv::TermCriteria::EPS, 30, 0.01);
    std::vector<std::uint8_t> ok_forward, ok_back;
    std::vector<float> error;
    const cv::Size window(options.track_window_px, options.track_window_px);
    cv::calcOpticalFlowPyrLK(from.levels, to.levels, points, forward, ok_forward, error, window,
                             levels, stop, flags);
    if (guessed) {
        back.resize(points.size());
        for (std::size_t k = 0; k < points.size(); ++k) back[k] = forward[k] - guess[k] + points[k];
    }
    cv::calcOpticalFlowPyrLK(to.levels, from.levels, forward, back, ok_back, error, window, levels,
                             stop, flags);
    for (std::size_t k = 0; k < points.size(); ++k) {
        const cv::Point2f& f = forward[k];
        ok[k] = ok_forward[k] && ok_back[k] &&
                cv::norm(back[k] - points[k]) <= options.max_round_trip_px && f.x >= 0.0f &&
                f.y >= 0.0f && f.x <= static_cast<float>(w - 1) && f.y <= static_cast<float>(h - 1);
    }
    return forward;
}

cv::Matx33d intrinsics(const StereoCamera& camera) {
    return {camera.fx_px, 0.0, camera.cx_px, 0.0, camera.fy_px, camera.cy_px, 0.0, 0.0, 1.0};
}

/// A motion and the correspondences it agrees with.
struct MotionFit {
    MotionEstimate estimate;
    Correspondences inliers;
};

/// The motion with the points lifted at offset_px: RANSAC over P3P, then Levenberg-Marquardt on
/// the inliers.
void solve_motion(const Correspondences& c, const StereoCamera& camera,
                  const OdometryOptions& options, double offset_px, MotionFit& out) {
    const std::vector<cv::Point3f> object = object_points(c, camera, offset_px);
    const cv::Matx33d K = intrinsics(camera);
    cv::Mat rvec, tvec;
    std::vector<int> inliers;
    const bool found = cv::solvePnPRansac(
        object, c.image, K, cv::noArray(), rvec, tvec, false, options.ransac_iterations,
        static_cast<float>(options.ransac_threshold_px), 0.999, inliers, cv::SOLVEPNP_P3P);
    out.estimate.inliers = static_cast<int>(inliers.size());
    if (!found || out.estimate.inliers < options.min_inliers) return;
    std::vector<cv::Point3f> in_object;
    for (int k : inliers) {
        const auto i = static_cast<std::size_t>(k);
        in_object.push_back(object[i]);
        out.inliers.corner.push_back(c.corner[i]);
        out.inliers.disparity_px.push_back(c.disparity_px[i]);
        out.inliers.image.push_back(c.image[i]);
    }
    cv::solvePnPRefineLM(in_object, out.inliers.image, K, cv::noArray(), rvec, tvec);
    out.estimate.T_curr_prev = pose_of(rvec, tvec);
    out.estimate.valid = out.estimate.T_curr_prev.allFinite();
}

/// T_curr_prev refined by Levenberg-Marquardt on the correspondences lifted at offset_px.
Pose refined(const Correspondences& c, const StereoCamera& camera, double offset_px,
             const Pose& T_curr_prev) {
    cv::Mat R, rvec, tvec;
    cv::eigen2cv(Eigen::Matrix3d(T_curr_prev.topLeftCorner<3, 3>()), R);
    cv::Rodrigues(R, rvec);
    cv::eigen2cv(Eigen::Vector3d(T_curr_prev.topRightCorner<3, 1>()), tvec);
    cv::solvePnPRefineLM(object_points(c, camera, offset_px), c.image, intrinsics(camera),
                         cv::noArray(), rvec, tvec);
    const Pose T = pose_of(rvec, tvec);
    return T.allFinite() ? T : T_curr_prev;
}

/// The disparity offset one frame pair measures, with its variance.
struct OffsetMeasurement {
    double offset_px = 0.0;
    double variance_px2 = 0.0;
};

/// The pixel of the left image where camera point q (z > 0) is seen.
Eigen::Vector2d image_point(const StereoCamera& camera, const Eigen::Vector3d& q) {
    return {camera.fx_px * q.x() / q.z() + camera.cx_px,
            camera.fy_px * q.y() / q.z() + camera.cy_px};
}

/// The reprojection residuals of the correspondences under the motion (axis-angle, translation)
/// and disparity offset packed in x; false where a point would lie behind a camera.
bool reprojection_residuals(const Correspondences& c, const StereoCamera& camera,
                            const Eigen::Matrix<double, 7, 1>& x, Eigen::VectorXd& r) {
    const Eigen::Vector3d w = x.head<3>();
    const Eigen::Matrix3d R = w.norm() > 0.0
                                  ? Eigen::AngleAxisd(w.norm(), w.normalized()).toRotationMatrix()
                                  : Eigen::Matrix3d::Identity();
    for (std::size_t k = 0; k < c.corner.size(); ++k) {
        const Eigen::Vector3d p = lifted(c.corner[k], c.disparity_px[k], camera, x[6]);
        if (!(p.z() > 0.0)) return false;
        const Eigen::Vector3d q = R * p + x.segment<3>(3);
        if (!(q.z() > 0.0)) return false;
        const auto i = static_cast<Eigen::Index>(2 * k);
        const Eigen::Vector2d seen = image_point(camera, q);
        r[i] = seen.x() - double{c.image[k].x};
        r[i + 1] = seen.y() - double{c.image[k].y};
    }
    return true;
}

/// The disparity offset that makes the pair's motion parallax consistent: Gauss-Newton over
/// the motion and the offset together, from the motion fitted at offset_px. Moving forward by
/// s, a point's image motion grows as s (d + offset) / (f B): its slope over the points'
/// disparities gives s, its intercept the offset. The variance is the fit's (residual variance
/// times the offset's entry of the inverse normal matrix); without translation it is large and
/// the pair says little. Empty when the fit fails.
std::optional<OffsetMeasurement> offset_from_parallax(const Correspondences& c,
                                                      const StereoCamera& camera,
                                                      const Pose& T_curr_prev, double offset_px) {
    using Vector7 = Eigen::Matrix<double, 7, 1>;
    const auto m = static_cast<Eigen::Index>(2 * c.corner.size());
    if (m <= 7) return std::nullopt;
    Vector7 x;
    const Eigen::AngleAxisd a(Eigen::Matrix3d(T_curr_prev.topLeftCorner<3, 3>()));
    x << a.angle() * a.axis(), T_curr_prev.topRightCorner<3, 1>(), offset_px;
    // Central differences: 1e-6 rad, 1e-6 m, 1e-4 px.
    const Vector7 step = (Vector7() << 1e-6, 1e-6, 1e-6, 1e-6, 1e-6, 1e-6, 1e-4).finished();
    Eigen::VectorXd r(m), plus(m), minus(m);
    Eigen::MatrixXd J(m, 7);
    for (int iteration = 0; iteration < 10; ++iteration) {
        if (!reprojection_residuals(c, camera, x, r)) return std::nullopt;
        for (int j = 0; j < 7; ++j) {
            Vector7 xp = x, xm = x;
            xp[j] += step[j];
            xm[j] -= step[j];
            if (!reprojection_residuals(c, camera, xp, plus) ||
                !reprojection_residuals(c, camera, xm, minus)) {
                return std::nullopt;
            }
            J.col(j) = (plus - minus) / (2.0 * step[j]);
        }
        const Eigen::Matrix<double, 7, 7> normal = J.transpose() * J;
        const Vector7 dx = normal.ldlt().solve(-J.transpose() * r);
        if (!dx.allFinite()) return std::nullopt;
        x += dx;
        if (std::abs(dx[6]) < 1e-4 && dx.head<6>().norm() < 1e-8) break;
    }
    if (!reprojection_residuals(c, camera, x, r)) return std::nullopt;
    const Eigen::Matrix<double, 7, 7> normal = J.transpose() * J;
    const double sigma2 = r.squaredNorm() / static_cast<double>(m - 7);
    const double variance = sigma2 * normal.inverse()(6, 6);
    if (!std::isfinite(x[6]) || !(variance > 0.0) || !std::isfinite(variance)) return std::nullopt;
    return OffsetMeasurement{x[6], variance};
}

/// The images and disparity of a frame pair: one size, or std::invalid_argument.
void check_sizes(const OdometryFrame& prev, const ImageU8& curr_left) {
    const int w = prev.left.width_px, h = prev.left.height_px;
    if (curr_left.width_px != w || curr_left.height_px != h || prev.disparity.width_px != w ||
        prev.disparity.height_px != h) {
        throw std::invalid_argument("estimate_motion: images and disparity differ in size");
    }
    const auto n = static_cast<std::size_t>(w) * static_cast<std::size_t>(h);
    if (!prev.static_mask.empty() && prev.static_mask.size() != n) {
        throw std::invalid_argument("estimate_motion: static mask differs in size");
    }
}

/// The landmarks with their tracked pixels where `ok`.
Correspondences correspondences(const Landmarks& l, const std::vector<cv::Point2f>& image,
                                const std::vector<char>& ok) {
    Correspondences c;
    for (std::size_t k = 0; k < l.corner.size(); ++k) {
        if (!ok[k]) continue;
        c.corner.push_back(l.corner[k]);
        c.disparity_px.push_back(l.disparity_px[k]);
        c.image.push_back(image[k]);
    }
    return c;
}

/// The motion fitted to correspondences at offset_px, or an invalid estimate with too few.
MotionFit fit_motion(const Correspondences& c, const StereoCamera& camera,
                     const OdometryOptions& options, double offset_px) {
    MotionFit out;
    out.estimate.disparity_offset_px = offset_px;
    out.estimate.tracked = static_cast<int>(c.corner.size());
    if (out.estimate.tracked >= options.min_inliers) {
        solve_motion(c, camera, options, offset_px, out);
    }
    return out;
}

/// Where the motion T_curr_prev takes each landmark lifted at offset_px, as a pixel of the
/// current image; a point it puts behind the camera stays where it was.
std::vector<cv::Point2f> predicted_pixels(const Landmarks& l, const StereoCamera& camera,
                                          double offset_px, const Pose& T_curr_prev) {
    std::vector<cv::Point2f> out;
    out.reserve(l.corner.size());
    const Eigen::Matrix3d R = T_curr_prev.topLeftCorner<3, 3>();
    const Eigen::Vector3d t = T_curr_prev.topRightCorner<3, 1>();
    for (std::size_t k = 0; k < l.corner.size(); ++k) {
        const Eigen::Vector3d q = R * lifted(l.corner[k], l.disparity_px[k], camera, offset_px) + t;
        if (!(q.z() > 0.0)) {
            out.push_back(l.corner[k]);
            continue;
        }
        const Eigen::Vector2d seen = image_point(camera, q);
        out.emplace_back(static_cast<float>(seen.x()), static_cast<float>(seen.y()));
    }
    return out;
}

/// The motion expected between two frames (the last one), and the inliers it gave.
struct Prediction {
    Pose T_curr_prev;
    int inliers = 0;
};

/// estimate_motion with the two left images' pyramids built. With `prediction`, the tracks
/// start where its motion puts the corners.
MotionFit motion(const OdometryFrame& prev, const VisualOdometry::Pyramid& prev_pyramid,
                 const ImageU8& curr_left, const VisualOdometry::Pyramid& curr_pyramid,
                 const StereoCamera& camera, const OdometryOptions& options, double offset_px,
                 const std::optional<Prediction>& prediction = std::nullopt) {
    check_sizes(prev, curr_left);
    const Landmarks l = landmarks_of(prev, prev_pyramid, camera, options);
    std::vector<char> ok;
    const auto fit = [&](const std::vector<cv::Point2f>& guess) {
        const std::vector<cv::Point2f> image =
            tracked(prev_pyramid, curr_pyramid, l.corner, guess, curr_left.width_px,
                    curr_left.height_px, options, ok);
        return fit_motion(correspondences(l, image, ok), camera, options, offset_px);
    };
    if (!prediction) return fit({});
    // A motion that changed more than the few pixels the predicted tracks can climb (a car
    // braking hard, a bump) loses most corners: fewer than half the last motion's inliers
    // agree. Then the tracks are redone from scratch, and the fit with more inliers kept.
    MotionFit guessed = fit(predicted_pixels(l, camera, offset_px, prediction->T_curr_prev));
    if (guessed.estimate.valid && 2 * guessed.estimate.inliers >= prediction->inliers) {
        return guessed;
    }
    MotionFit scratch = fit({});
    return scratch.estimate.inliers > guessed.estimate.inliers || !guessed.estimate.valid ? scratch
                                                                                          : guessed;
}

}  // namespace

MotionEstimate estimate_motion(const OdometryFrame& prev, const ImageU8& curr_left,
                               const StereoCamera& camera, const OdometryOptions& options,
                               double disparity_offset_px) {
    options.validate();
    return motion(prev, pyramid_of(grey_of(prev.left), options), curr_left,
                  pyramid_of(grey_of(curr_left), options), camera, options, disparity_offset_px)
        .estimate;
}

ImageU8 grey_image(const ImageU8& image) {
    if (image.channels == 1 || image.empty()) return image;
    ImageU8 out{image.width_px, image.height_px, 1,
                std::vector<std::uint8_t>(static_cast<std::size_t>(image.width_px) *
                                          static_cast<std::size_t>(image.height_px))};
    cv::Mat grey(out.height_px, out.width_px, CV_8UC1, out.data.data());
    cv::cvtColor(mat_view(image), grey, cv::COLOR_RGB2GRAY);
    return out;
}

std::vector<std::uint8_t> static_mask(const std::vector<std::uint16_t>& class_index,
                                      const std::vector<char>& is_thing) {
    // Every 16-bit index looked up in one table: no branch per pixel.
    std::vector<std::uint8_t> votes(std::size_t{1} << 16, 1);
    for (std::size_t k = 0; k < std::min(is_thing.size(), votes.size()); ++k) {
        if (is_thing[k]) votes[k] = 0;
    }
    std::vector<std::uint8_t> out(class_index.size());
    std::transform(class_index.begin(), class_index.end(), out.begin(),
                   [&](std::uint16_t k) { return votes[k]; });
    return out;
}

VisualOdometry::VisualOdometry(const StereoCamera& camera, const OdometryOptions& options)
    : camera_(camera), options_(options) {
    options_.validate();
    offset_.information =
        1.0 / (options_.disparity_offset_prior_px * options_.disparity_offset_prior_px);
}

VisualOdometry::~VisualOdometry() = default;

Pose VisualOdometry::add(OdometryFrame frame) {
    // Grey once: the left image is tracked from twice (into this frame and the next).
    if (frame.left.channels != 1) frame.left = grey_image(frame.left);
    if (frame.right.channels != 1) frame.right = grey_image(frame.right);
    auto pyramid = std::make_unique<Pyramid>(pyramid_of(grey_of(frame.left), options_));
    if (prev_) {
        MotionFit fit = motion(
            *prev_, *prev_pyramid_, frame.left, *pyramid, camera_, options_, offset_.mean_px,
            last_.valid ? std::optional<Prediction>({velocity_, last_.inliers}) : std::nullopt);
        if (fit.estimate.valid && options_.estimate_disparity_offset) {
            if (const auto m = offset_from_parallax(fit.inliers, camera_, fit.estimate.T_curr_prev,
                                                    offset_.mean_px)) {
                // One Gaussian update of a constant: the pair's measurement by its information.
                const double information = 1.0 / m->variance_px2;
                offset_.mean_px =
                    (offset_.information * offset_.mean_px + information * m->offset_px) /
                    (offset_.information + information);
                offset_.information += information;
                fit.estimate.T_curr_prev =
                    refined(fit.inliers, camera_, offset_.mean_px, fit.estimate.T_curr_prev);
                fit.estimate.disparity_offset_px = offset_.mean_px;
            }
        }
        last_ = fit.estimate;
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
