#include <cmath>
#include <random>
#include <vector>

#include <Eigen/Geometry>
#include <catch2/catch.hpp>
#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>

#include "cloud_analysis/evaluation/odometry_eval.hpp"
#include "cloud_analysis/odometry/visual_odometry.hpp"
#include "stereoscene/support/angles.hpp"

using stereoscene::support::kPi;

using namespace cloud_analysis;
using odometry::Pose;

namespace {

/// A KITTI-like rig at a fifth of the size's focal length: 320 x 240, fx 300 px, baseline 0.5 m.
StereoCamera rig() {
    StereoCamera c;
    c.width_px = 320;
    c.height_px = 240;
    c.fx_px = c.fy_px = 300.0;
    c.cx_px = c.cx_right_px = 160.0;
    c.cy_px = 120.0;
    c.baseline_m = 0.5;
    return c;
}

/// A textured wall facing the camera at depth z_m, seen by a camera at (x_m, 0, 0) looking
/// along +z: each pixel samples the wall's texture at the point its ray meets.
ImageU8 view_of_wall(const cv::Mat& texture, double x_m, double z_m, const StereoCamera& c) {
    // Texture: 1 texel = 1 cm, centred on the optical axis of the camera at x = 0.
    cv::Mat map_x(c.height_px, c.width_px, CV_32F), map_y(c.height_px, c.width_px, CV_32F);
    for (int v = 0; v < c.height_px; ++v) {
        for (int u = 0; u < c.width_px; ++u) {
            const double wx = x_m + (u - c.cx_px) * z_m / c.fx_px;
            const double wy = (v - c.cy_px) * z_m / c.fy_px;
            map_x.at<float>(v, u) = static_cast<float>(texture.cols / 2 + wx * 100.0);
            map_y.at<float>(v, u) = static_cast<float>(texture.rows / 2 + wy * 100.0);
        }
    }
    cv::Mat out;
    cv::remap(texture, out, map_x, map_y, cv::INTER_LINEAR);
    ImageU8 image{c.width_px, c.height_px, 1, std::vector<std::uint8_t>(out.total())};
    std::copy(out.data, out.data + out.total(), image.data.begin());
    return image;
}

cv::Mat texture() {
    cv::Mat t(3000, 3000, CV_8U);
    cv::RNG rng(7);
    rng.fill(t, cv::RNG::UNIFORM, 0, 255);
    cv::GaussianBlur(t, t, cv::Size(0, 0), 3.0);
    cv::normalize(t, t, 0, 255, cv::NORM_MINMAX);
    return t;
}

/// Two textured walls facing the camera, the left half of the view (x < 0) at 6 m and the right
/// half at 11 m in the first camera's frame, seen by a camera at (0, 0, tz_m) looking along +z;
/// and their true disparity.
struct TwoWallView {
    ImageU8 image;
    DisparityMap disparity;
};
TwoWallView view_of_two_walls(const cv::Mat& texture, double tz_m, const StereoCamera& c) {
    cv::Mat map_x(c.height_px, c.width_px, CV_32F), map_y(c.height_px, c.width_px, CV_32F);
    TwoWallView out;
    out.disparity = DisparityMap{c.width_px, c.height_px, {}};
    for (int v = 0; v < c.height_px; ++v) {
        for (int u = 0; u < c.width_px; ++u) {
            const double a = (u - c.cx_px) / c.fx_px, b = (v - c.cy_px) / c.fy_px;
            const bool near = a < 0.0;
            const double depth = (near ? 6.0 : 11.0) - tz_m;
            // Each wall its own part of the texture (1 texel = 1 cm).
            const double wall_offset = near ? -700.0 : 700.0;
            map_x.at<float>(v, u) =
                static_cast<float>(texture.cols / 2 + wall_offset + depth * a * 100.0);
            map_y.at<float>(v, u) = static_cast<float>(texture.rows / 2 + depth * b * 100.0);
            out.disparity.disparity_px.push_back(
                static_cast<float>(c.fx_px * c.baseline_m / depth));
        }
    }
    cv::Mat grey;
    cv::remap(texture, grey, map_x, map_y, cv::INTER_LINEAR);
    out.image = ImageU8{c.width_px, c.height_px, 1, std::vector<std::uint8_t>(grey.total())};
    std::copy(grey.data, grey.data + grey.total(), out.image.data.begin());
    return out;
}

/// Straight path along z, one pose a metre.
std::vector<Pose> straight(int frames, double step_m) {
    std::vector<Pose> out;
    for (int i = 0; i < frames; ++i) {
        Pose T = Pose::Identity();
        T(2, 3) = step_m * i;
        out.push_back(T);
    }
    return out;
}

}  // namespace

TEST_CASE("the camera's motion towards a textured wall is found from the stereo pair",
          "[odometry]") {
    const StereoCamera c = rig();
    const cv::Mat tex = texture();
    const double z = 8.0;  // 18.75 px of disparity
    odometry::OdometryFrame prev;
    prev.left = view_of_wall(tex, 0.0, z, c);
    prev.right = view_of_wall(tex, c.baseline_m, z, c);
    prev.disparity.width_px = c.width_px;
    prev.disparity.height_px = c.height_px;
    prev.disparity.disparity_px.assign(prev.left.data.size(),
                                       static_cast<float>(c.fx_px * c.baseline_m / z));
    // The camera moves 0.8 m forward and 0.3 m to the right.
    const ImageU8 curr = view_of_wall(tex, 0.3, z - 0.8, c);
    const odometry::MotionEstimate m =
        odometry::estimate_motion(prev, curr, c, odometry::OdometryOptions{});
    REQUIRE(m.valid);
    CHECK(m.inliers >= 50);
    // Points move the other way in the camera's frame.
    CHECK(m.T_curr_prev(0, 3) == Approx(-0.3).margin(0.03));
    CHECK(m.T_curr_prev(1, 3) == Approx(0.0).margin(0.03));
    CHECK(m.T_curr_prev(2, 3) == Approx(-0.8).margin(0.04));
    CHECK(Eigen::AngleAxisd(Eigen::Matrix3d(m.T_curr_prev.topLeftCorner<3, 3>())).angle() < 0.01);
    // Chained, the second frame sits 0.8 m ahead in the first frame's world.
    odometry::VisualOdometry vo(c, odometry::OdometryOptions{});
    CHECK(vo.add(prev).isApprox(Pose::Identity()));
    odometry::OdometryFrame next = prev;
    next.left = curr;
    const Pose T_world_curr = vo.add(next);
    CHECK(T_world_curr(2, 3) == Approx(0.8).margin(0.04));
    CHECK(T_world_curr(0, 3) == Approx(0.3).margin(0.03));
}

TEST_CASE("a rig's disparity offset is found from the motion's parallax and corrected",
          "[odometry]") {
    const StereoCamera c = rig();
    const cv::Mat tex = texture();
    // The matcher reads every disparity 0.5 px low (points 2-4 % too far): the rig's
    // offset is +0.5 px. The camera drives 0.8 m a frame towards two walls (6 and 11 m).
    const double offset_px = 0.5, step_m = 0.8;
    const int frames = 5;
    const auto drive = [&](bool estimate) {
        odometry::OdometryOptions options;
        options.estimate_disparity_offset = estimate;
        odometry::VisualOdometry vo(c, options);
        Pose last = Pose::Identity();
        for (int i = 0; i < frames; ++i) {
            TwoWallView view = view_of_two_walls(tex, step_m * i, c);
            for (float& d : view.disparity.disparity_px) d -= static_cast<float>(offset_px);
            odometry::OdometryFrame frame;
            frame.left = view.image;
            frame.disparity = view.disparity;  // no right image: the dense disparity as it is
            last = vo.add(frame);
            REQUIRE((i == 0 || vo.last_motion().valid));
        }
        return std::make_pair(last(2, 3), vo.disparity_offset_px());
    };
    const double driven_m = step_m * (frames - 1);
    const auto [z_estimated, offset_estimated] = drive(true);
    CHECK(offset_estimated == Approx(offset_px).margin(0.1));
    CHECK(z_estimated == Approx(driven_m).epsilon(0.01));
    // Taken as they are, the low disparities make the path too long.
    const auto [z_fixed, offset_fixed] = drive(false);
    CHECK(offset_fixed == 0.0);
    CHECK(z_fixed > driven_m * 1.02);
}

TEST_CASE("a drive that stops at once is followed: the tracks start again from scratch",
          "[odometry]") {
    const StereoCamera c = rig();
    const cv::Mat tex = texture();
    odometry::VisualOdometry vo(c, odometry::OdometryOptions{});
    // 0.8 m a frame towards two walls (6 and 11 m), then standing still: the last motion puts
    // the near wall's corners up to 15 px from where they are.
    bool first = true;
    for (const double z : {0.0, 0.8, 1.6, 2.4, 2.4, 2.4}) {
        const TwoWallView view = view_of_two_walls(tex, z, c);
        odometry::OdometryFrame frame;
        frame.left = view.image;
        frame.disparity = view.disparity;
        const Pose T_world_curr = vo.add(frame);
        CHECK(T_world_curr(2, 3) == Approx(z).margin(0.04));
        if (!first) {
            REQUIRE(vo.last_motion().valid);
            CHECK(vo.last_motion().inliers >= 300);  // most of the corners, not a few
        }
        first = false;
    }
    CHECK(vo.last_motion().T_curr_prev.topRightCorner<3, 1>().norm() < 0.01);
}

TEST_CASE("a camera standing still says nothing of the disparity offset", "[odometry]") {
    const StereoCamera c = rig();
    const TwoWallView view = view_of_two_walls(texture(), 0.0, c);
    odometry::VisualOdometry vo(c, odometry::OdometryOptions{});
    odometry::OdometryFrame frame;
    frame.left = view.image;
    frame.disparity = view.disparity;
    Pose last = Pose::Identity();
    for (int i = 0; i < 4; ++i) last = vo.add(frame);
    CHECK(vo.last_motion().valid);
    CHECK(last.topRightCorner<3, 1>().norm() < 0.01);
    // Without parallax the offset keeps its prior's mean.
    CHECK(std::abs(vo.disparity_offset_px()) < 0.05);
}

TEST_CASE("points on things that may move do not vote", "[odometry]") {
    const StereoCamera c = rig();
    const cv::Mat tex = texture();
    odometry::OdometryFrame prev;
    prev.left = view_of_wall(tex, 0.0, 8.0, c);
    prev.right = view_of_wall(tex, 0.5, 8.0, c);
    prev.disparity.width_px = c.width_px;
    prev.disparity.height_px = c.height_px;
    prev.disparity.disparity_px.assign(prev.left.data.size(), 18.75f);
    const ImageU8 curr = view_of_wall(tex, 0.0, 7.5, c);
    CHECK(odometry::estimate_motion(prev, curr, c, odometry::OdometryOptions{}).valid);
    prev.static_mask.assign(prev.left.data.size(), 0);  // everything a thing: nothing votes
    const auto m = odometry::estimate_motion(prev, curr, c, odometry::OdometryOptions{});
    CHECK_FALSE(m.valid);
    CHECK(m.tracked == 0);
    CHECK(odometry::static_mask({0, 1, 2, 0xFFFF}, {0, 1, 0}) ==
          std::vector<std::uint8_t>{1, 0, 1, 1});
}

TEST_CASE("KITTI pose files round-trip and bad ones name their line", "[odometry]") {
    const std::vector<Pose> poses = straight(3, 1.5);
    const std::string text = odometry::format_kitti_poses(poses);
    const auto back = odometry::parse_kitti_poses(text, "p.txt");
    REQUIRE(back.size() == 3);
    CHECK(back[2].isApprox(poses[2]));
    CHECK_THROWS_WITH(odometry::parse_kitti_poses("1 0 0 0 0 1 0 0 0 0 1\n", "p.txt"),
                      Catch::Contains("p.txt, line 1: expected 12 numbers"));
    CHECK_THROWS_WITH(odometry::parse_kitti_poses("1 0 0 0\n1 0 0 0 0 1 0 0 0 0 1 x\n", "p.txt"),
                      Catch::Contains("p.txt, line 1"));
    CHECK_THROWS_WITH(odometry::parse_kitti_poses("\n", "p.txt"), Catch::Contains("no poses"));
}

TEST_CASE("odometry scores are KITTI's: a path 2 % too long errs 2 % per metre",
          "[odometry][evaluation]") {
    const std::vector<Pose> truth = straight(31, 1.0);  // 30 m
    const OdometryErrors same = evaluate_odometry(truth, truth);
    CHECK(same.path_m == Approx(30.0));
    CHECK(same.translation_pct == Approx(0.0).margin(1e-9));
    CHECK(same.end_point_m == Approx(0.0).margin(1e-9));
    REQUIRE(same.lengths.size() == 3);      // 5, 10 and 20 m fit in 30 m
    CHECK(same.lengths[0].segments == 26);  // starts 0..25 reach 5 m further
    const OdometryErrors longer = evaluate_odometry(straight(31, 1.02), truth);
    CHECK(longer.translation_pct == Approx(2.0).epsilon(1e-6));
    CHECK(longer.rotation_deg_per_m == Approx(0.0).margin(1e-9));
    CHECK(longer.end_point_m == Approx(0.6));
    CHECK(longer.end_point_pct == Approx(2.0));
    // A constant yaw of 0.1 degree a metre: over any segment of L metres the rotation error is
    // 0.1 L degrees, 0.1 degree per metre.
    std::vector<Pose> turning = truth;
    for (std::size_t i = 0; i < turning.size(); ++i) {
        turning[i].topLeftCorner<3, 3>() =
            Eigen::AngleAxisd(0.1 * static_cast<double>(i) * kPi / 180.0, Eigen::Vector3d::UnitY())
                .toRotationMatrix();
    }
    CHECK(evaluate_odometry(turning, truth).rotation_deg_per_m == Approx(0.1).epsilon(1e-6));
    CHECK_THROWS_WITH(evaluate_odometry(straight(3, 1.0), truth),
                      Catch::Contains("differ in frames: 3 and 31"));
    CHECK(segment_lengths(250.0) == std::vector<double>{5, 10, 20, 50, 100, 200});
}
