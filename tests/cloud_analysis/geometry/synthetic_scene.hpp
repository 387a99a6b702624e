#pragma once

// Scenes for the stereo-only path's tests: a flat road and upright boxes ray-cast into a
// disparity map, and where a point of them lands in the image.

#include <string>
#include <utility>
#include <vector>

#include "cloud_analysis/cloud/semantic.hpp"
#include "cloud_analysis/geometry/scene_geometry.hpp"

namespace test_scenes {

using cloud_analysis::DisparityMap;
using cloud_analysis::kNoDisparity;
using cloud_analysis::StereoCamera;
using cloud_analysis::geometry::SceneGeometry;

/// An upright box (x from x0 to x1, face at depth z, from bottom_m above the road up to top_m)
/// in a scene.
struct Box {
    double x0, x1, z, top_m;
    double bottom_m = 0.0;
};

/// `boxes` and a car seen from behind, its back at depth z: the back up to the boot lid, the
/// cabin 0.6 m farther up to the roof.
inline std::vector<Box> with_car_from_behind(std::vector<Box> boxes, double z) {
    boxes.push_back({-1.0, 0.8, z, 1.0});
    boxes.push_back({-0.8, 0.6, z + 0.6, 1.5});
    return boxes;
}

/// Ray casting of a flat road `height_m` below the camera (pitch 0) and upright boxes facing
/// the camera; sky (no disparity) above the horizon where nothing is hit.
inline DisparityMap render(const StereoCamera& c, double height_m, const std::vector<Box>& boxes) {
    DisparityMap d;
    d.width_px = c.width_px;
    d.height_px = c.height_px;
    d.disparity_px.assign(static_cast<std::size_t>(c.width_px) * c.height_px, kNoDisparity);
    const double fb = c.fx_px * c.baseline_m;
    for (int v = 0; v < c.height_px; ++v) {
        const double y = (v - c.cy_px) / c.fy_px;  // ray (x, y, 1)
        for (int u = 0; u < c.width_px; ++u) {
            const double x = (u - c.cx_px) / c.fx_px;
            double z = y > 1e-6 ? height_m / y : 1e9;
            for (const Box& b : boxes) {
                const double px = x * b.z, py = y * b.z;
                if (b.z < z && px >= b.x0 && px <= b.x1 && py <= height_m &&
                    py >= height_m - b.top_m && py <= height_m - b.bottom_m) {
                    z = b.z;
                }
            }
            if (z < 200.0) {
                d.disparity_px[static_cast<std::size_t>(v) * c.width_px + u] =
                    static_cast<float>(fb / z);
            }
        }
    }
    return d;
}

inline std::string class_at(const SceneGeometry& g, const cloud_analysis::Palette& p, int u,
                            int v) {
    const auto c = g.classes.class_index[static_cast<std::size_t>(v) * g.classes.width_px + u];
    return c == cloud_analysis::kVoidClass ? "void" : p.classes[c].name;
}

/// Pixel of the point (x, height above road, z) for the rig at 1.65 m.
inline std::pair<int, int> pixel_of(const StereoCamera& c, double x, double up_m, double z) {
    return {static_cast<int>(c.cx_px + c.fx_px * x / z),
            static_cast<int>(c.cy_px + c.fy_px * (1.65 - up_m) / z)};
}

}  // namespace test_scenes
