#pragma once

/// The KITTI rig at its image size, for tests that need a real camera's numbers.

#include "cloud_analysis/cloud/types.hpp"
#include "scene_schema/entities.hpp"

namespace test_rigs {

/// KITTI's rig: fx = fy = 721.5 px, principal point (621, 187.5), 1242 x 375 px, baseline
/// 0.54 m.
inline cloud_analysis::StereoCamera kitti_rig() {
    cloud_analysis::StereoCamera c;
    c.width_px = 1242;
    c.height_px = 375;
    c.fx_px = c.fy_px = 721.5;
    c.cx_px = c.cx_right_px = 621.0;
    c.cy_px = 187.5;
    c.baseline_m = 0.54;
    return c;
}

/// KITTI's left colour camera as an entity file's frame.camera: P_rect_02 of the 2011_09_26
/// calibration (fx = fy = 721.5377 px, principal point (609.5593, 172.854)), 1242 x 375 px,
/// baseline 0.54 m.
inline scene_schema::CameraIntrinsics kitti_intrinsics() {
    scene_schema::CameraIntrinsics c;
    c.width_px = 1242;
    c.height_px = 375;
    c.fx_px = c.fy_px = 721.5377;
    c.cx_px = 609.5593;
    c.cy_px = 172.854;
    c.baseline_m = 0.54;
    return c;
}

}  // namespace test_rigs
