// KITTI label_2 locations are in rectified camera 0; our entities are in the pair's left camera
// (camera 2). These tests check the conversion against KITTI's own projection with P2.

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <limits>
#include <sstream>
#include <string>
#include <vector>

#include <Eigen/Core>
#include <catch2/catch.hpp>

#include "cloud_analysis/evaluation/kitti_labels.hpp"
#include "cloud_analysis/stereo/calibration.hpp"

namespace {

using cloud_analysis::KittiLabel;
using cloud_analysis::LabelFrame;

// A KITTI object calibration: camera 2 sits about 6 cm right of camera 0 (P2[0,3] / fx).
const char* kObjectCalib =
    "P0: 721.5377 0 609.5593 0 0 721.5377 172.854 0 0 0 1 0\n"
    "P1: 721.5377 0 609.5593 -387.5744 0 721.5377 172.854 0 0 0 1 0\n"
    "P2: 721.5377 0 609.5593 44.85728 0 721.5377 172.854 0.2163791 0 0 1 0.002745884\n"
    "P3: 721.5377 0 609.5593 -339.5242 0 721.5377 172.854 2.199936 0 0 1 0.002729905\n";

Eigen::Matrix<double, 3, 4> p2_of(const std::string& text) {
    std::istringstream in(text);
    std::string line;
    while (std::getline(in, line)) {
        if (line.rfind("P2:", 0) != 0) continue;
        std::istringstream values(line.substr(3));
        Eigen::Matrix<double, 3, 4> P;
        for (int r = 0; r < 3; ++r)
            for (int c = 0; c < 4; ++c) values >> P(r, c);
        return P;
    }
    FAIL("no P2 line");
    return {};
}

/// KITTI devkit's 2D box of a label: the 8 corners of the 3D box in camera 0, projected with
/// P2 (computeBox3D + projectToImage), clipped to the image.
std::array<double, 4> devkit_box(const KittiLabel& l, const Eigen::Matrix<double, 3, 4>& P2,
                                 double width, double height) {
    const double c = std::cos(l.rotation_y), s = std::sin(l.rotation_y);
    double u0 = std::numeric_limits<double>::max(), v0 = u0, u1 = -u0, v1 = -u0;
    for (int i = 0; i < 8; ++i) {
        const double x = ((i & 1) ? 0.5 : -0.5) * l.l, z = ((i & 2) ? 0.5 : -0.5) * l.w;
        const double y = (i & 4) ? -l.h : 0.0;  // y is the box bottom in label_2
        const Eigen::Vector4d X(l.x + c * x + s * z, l.y + y, l.z - s * x + c * z, 1.0);
        const Eigen::Vector3d p = P2 * X;
        u0 = std::min(u0, p.x() / p.z());
        u1 = std::max(u1, p.x() / p.z());
        v0 = std::min(v0, p.y() / p.z());
        v1 = std::max(v1, p.y() / p.z());
    }
    return {std::clamp(u0, 0.0, width - 1), std::clamp(v0, 0.0, height - 1),
            std::clamp(u1, 0.0, width - 1), std::clamp(v1, 0.0, height - 1)};
}

scene_schema::CameraIntrinsics camera_of(const cloud_analysis::Calibration& c, int w, int h) {
    scene_schema::CameraIntrinsics k;
    k.width_px = w;
    k.height_px = h;
    k.fx_px = c.camera.fx_px;
    k.fy_px = c.camera.fy_px;
    k.cx_px = c.camera.cx_px;
    k.cy_px = c.camera.cy_px;
    k.baseline_m = c.camera.baseline_m;
    return k;
}

/// Largest difference between our exported 2D box and the devkit's, px.
double box_difference(const KittiLabel& ours, const std::array<double, 4>& devkit) {
    double worst = 0.0;
    for (int i = 0; i < 4; ++i) worst = std::max(worst, std::abs(ours.bbox[i] - devkit[i]));
    return worst;
}

}  // namespace

TEST_CASE("a KITTI calibration says where the left camera sits in camera 0", "[kitti_labels]") {
    const auto calib = cloud_analysis::parse_calibration(kObjectCalib, "000001.txt");
    // t = K^-1 P2[:, 3]
    CHECK(calib.reference_offset_m.z() == Approx(0.002745884));
    CHECK(calib.reference_offset_m.x() ==
          Approx((44.85728 - 609.5593 * 0.002745884) / 721.5377).epsilon(1e-12));
    CHECK(calib.reference_offset_m.y() ==
          Approx((0.2163791 - 172.854 * 0.002745884) / 721.5377).epsilon(1e-12));
    const auto yaml = cloud_analysis::parse_calibration(
        "fx: 700\nfy: 700\ncx: 320\ncy: 240\nbaseline_m: 0.5\n", "rig.yaml");
    CHECK(yaml.reference_offset_m.isZero());
}

TEST_CASE("labels move into the left camera and back without loss", "[kitti_labels]") {
    const LabelFrame frame = cloud_analysis::label_frame_of(
        cloud_analysis::parse_calibration(kObjectCalib, "000001.txt"));
    const auto labels = cloud_analysis::parse_kitti_labels(
        "Car 0.00 0 1.85 387.63 181.54 423.81 203.12 1.67 1.87 3.69 -16.53 2.39 58.49 1.57\n",
        "000001.txt");
    const auto entities = cloud_analysis::entities_from_kitti_labels(labels, frame);
    REQUIRE(entities.size() == 1);
    CHECK(entities[0].x == Approx(-16.53 + frame.tx_m));
    CHECK(entities[0].x - (-16.53) == Approx(0.0599).margin(0.001));  // about 6 cm
    const KittiLabel back = cloud_analysis::kitti_label_from_entity(entities[0], nullptr, frame);
    CHECK(back.x == Approx(-16.53).margin(1e-12));
    CHECK(back.y == Approx(2.39).margin(1e-12));
    CHECK(back.z == Approx(58.49).margin(1e-12));
    CHECK(back.alpha == Approx(1.85).margin(0.005));  // KITTI's own alpha of this line
}

TEST_CASE("the exported 2D box is the devkit's projection of the label with P2", "[kitti_labels]") {
    const auto calib = cloud_analysis::parse_calibration(kObjectCalib, "000001.txt");
    const LabelFrame frame = cloud_analysis::label_frame_of(calib);
    const auto P2 = p2_of(kObjectCalib);
    const auto camera = camera_of(calib, 1242, 375);
    // A car 8 m ahead, 2 m left, turned 30 degrees: near enough that 6 cm is several pixels.
    KittiLabel l;
    l.type = "Car";
    l.h = 1.5;
    l.w = 1.8;
    l.l = 4.2;
    l.x = -2.0;
    l.y = 1.65;
    l.z = 8.0;
    l.rotation_y = 0.52;
    const auto entity = cloud_analysis::entities_from_kitti_labels({l}, frame).at(0);
    const auto devkit = devkit_box(l, P2, 1242, 375);
    CHECK(box_difference(cloud_analysis::kitti_label_from_entity(entity, &camera, frame), devkit) <
          0.05);
    // Reading the label as if it were in camera 2 (no frame) misses by P2[0,3] / z px.
    const auto naive = cloud_analysis::entities_from_kitti_labels({l}).at(0);
    CHECK(box_difference(cloud_analysis::kitti_label_from_entity(naive, &camera), devkit) > 3.0);
}

TEST_CASE("on KITTI object labels the exported 2D boxes are the devkit's",
          "[kitti_labels][kitti]") {
    const std::filesystem::path root =
        std::filesystem::path(STEREOSCENE_SHARED_DATA_DIR) / "kitti_object";
    int checked = 0;
    for (const char* id : {"000000", "000001", "000002"}) {
        const auto calib_path = root / "calib" / (std::string(id) + ".txt");
        std::ifstream in(calib_path);
        REQUIRE(in);
        const std::string text((std::istreambuf_iterator<char>(in)), {});
        const auto calib = cloud_analysis::parse_calibration(text, calib_path.string());
        const auto camera = camera_of(calib, 1242, 375);
        const LabelFrame frame = cloud_analysis::label_frame_of(calib);
        const auto labels =
            cloud_analysis::load_kitti_labels(root / "label_2" / (std::string(id) + ".txt"));
        for (const auto& l : labels) {
            if (l.type == "DontCare" || l.z < 1.0) continue;
            const auto entities = cloud_analysis::entities_from_kitti_labels({l}, frame);
            if (entities.empty()) continue;  // Misc: no class of ours
            const KittiLabel back =
                cloud_analysis::kitti_label_from_entity(entities[0], &camera, frame);
            INFO(id << " " << l.type << " at z " << l.z);
            CHECK(box_difference(back, devkit_box(l, p2_of(text), 1242, 375)) < 0.05);
            CHECK(back.x == Approx(l.x).margin(1e-9));
            CHECK(back.alpha == Approx(l.alpha).margin(0.011));  // labels have two decimals
            ++checked;
        }
    }
    CHECK(checked >= 4);
}
