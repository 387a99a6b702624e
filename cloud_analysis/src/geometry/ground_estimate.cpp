#include <cmath>
#include <sstream>
#include <stdexcept>
#include <vector>

#include "cloud_analysis/geometry/scene_geometry.hpp"
#include "stereoscene/support/angles.hpp"

using stereoscene::support::kDegPerRad;

namespace cloud_analysis::geometry {
namespace {

std::string metres(double value) {
    std::ostringstream s;
    s.precision(2);
    s << std::fixed << value << " m";
    return s.str();
}

}  // namespace

void GeometryOptions::validate() const {
    const auto fail_if = [](bool bad, const char* message) {
        if (bad) throw std::invalid_argument(message);
    };
    const auto positive = [](double v, const char* name) {
        if (!(v > 0.0)) throw std::invalid_argument(std::string(name) + ": must be > 0");
    };
    positive(ground_max_range_m, "geometry.ground_max_range_m");
    positive(ground_inlier_m, "geometry.ground_inlier_m");
    positive(ground_tolerance_m, "geometry.ground_tolerance_m");
    fail_if(!(disparity_noise_px >= 0.0), "geometry.disparity_noise_px: must be >= 0");
    positive(min_camera_height_m, "geometry.min_camera_height_m");
    fail_if(!(max_camera_height_m > min_camera_height_m),
            "geometry.max_camera_height_m: must be > geometry.min_camera_height_m");
    positive(max_depth_m, "geometry.max_depth_m");
    positive(max_obstacle_height_m, "geometry.max_obstacle_height_m");
    fail_if(column_bin_px < 1, "geometry.column_bin_px: must be >= 1");
    positive(link_depth_m, "geometry.link_depth_m");
    fail_if(!(disparity_bin_share > 0.0 && disparity_bin_share < 1.0),
            "geometry.disparity_bin_share: must be in (0, 1)");
    fail_if(min_cell_pixels < 1, "geometry.min_cell_pixels: must be >= 1");
    fail_if(blend_rows < 1 || blend_rows > 1000, "geometry.blend_rows: must be in [1, 1000]");
    fail_if(!(blend_step_px >= 0.0 && blend_step_px < 1e6), "geometry.blend_step_px: must be >= 0");
    fail_if(!(top_behind_px > 0.0 && top_behind_px < 1e6), "geometry.top_behind_px: must be > 0");
    fail_if(!(foot_ahead_px > 0.0 && foot_ahead_px < 1e6), "geometry.foot_ahead_px: must be > 0");
    fail_if(!(split_surface_px >= 0.0 && split_surface_px < 1e6),
            "geometry.split_surface_px: must be >= 0");
    fail_if(!(behind_gap_m >= 0.0 && behind_gap_m < 1e6), "geometry.behind_gap_m: must be >= 0");
    positive(car_min_height_m, "geometry.car_min_height_m");
    fail_if(!(car_max_height_m > car_min_height_m),
            "geometry.car_max_height_m: must be > car_min_height_m");
    positive(car_min_width_m, "geometry.car_min_width_m");
    positive(vehicle_piece_m, "geometry.vehicle_piece_m");
    fail_if(!(car_max_lean >= 0.0 && car_max_lean < 1e6), "geometry.car_max_lean: must be >= 0");
    positive(building_min_height_m, "geometry.building_min_height_m");
    positive(pole_max_width_m, "geometry.pole_max_width_m");
    positive(wall_top_spread_m, "geometry.wall_top_spread_m");
    positive(wall_top_spread_near_m, "geometry.wall_top_spread_near_m");
    positive(wall_near_depth_m, "geometry.wall_near_depth_m");
    positive(wall_max_thickness_m, "geometry.wall_max_thickness_m");
    positive(wall_min_width_m, "geometry.wall_min_width_m");
    positive(low_max_height_m, "geometry.low_max_height_m");
    fail_if(!(min_cell_height_m >= 0.0), "geometry.min_cell_height_m: must be >= 0");
    positive(low_cut_m, "geometry.low_cut_m");
    fail_if(threads < 1, "geometry.threads: must be >= 1");
    fail_if(segmentation != "columns" && segmentation != "clusters",
            "geometry.segmentation: must be columns or clusters");
    positive(cluster_distance_m, "geometry.cluster_distance_m");
    fail_if(!(layer_height_m > car_max_height_m),
            "geometry.layer_height_m: must be above car_max_height_m");
    fail_if(!(continuity_band_m > 0.0), "geometry.continuity_band_m: must be > 0");
    fail_if(!(continuity_behind_m >= 0.0 && continuity_behind_m < 1e6),
            "geometry.continuity_behind_m: must be >= 0");
    fail_if(!(continuity_behind_px > 0.0 && continuity_behind_px < 1e6),
            "geometry.continuity_behind_px: must be > 0");
    fail_if(!(continuity_share > 0.0 && continuity_share <= 1.0),
            "geometry.continuity_share: must be in (0, 1]");
    fail_if(green_window_px < 0 || green_window_px > 64,
            "geometry.green_window_px: must be in [0, 64]");
    fail_if(!(car_min_edge_share >= 0.0 && car_min_edge_share < 1.0),
            "geometry.car_min_edge_share: must be in [0, 1)");
    positive(edge_window_m, "geometry.edge_window_m");
    fail_if(edge_step_px < 1 || edge_step_px > 64, "geometry.edge_step_px: must be in [1, 64]");
    fail_if(!(min_face_share >= 0.0 && min_face_share < 1.0),
            "geometry.min_face_share: must be in [0, 1)");
    fail_if(!(green_fraction > 0.0 && green_fraction <= 1.0),
            "geometry.green_fraction: must be in (0, 1]");
}

GroundEstimate estimate_ground(const DisparityMap& disparity, const StereoCamera& camera,
                               const GeometryOptions& options) {
    options.validate();
    GroundEstimate out;
    const double fb = camera.fx_px * camera.baseline_m;
    const double offset_px = camera.cx_px - camera.cx_right_px;
    // The lower image (below the principal row) holds the road in front of a car's camera; every
    // 2nd row and 4th column is plenty for a plane (fit_ground_plane subsamples to 20k anyway).
    // Every depth is kept: a wrong baseline puts the whole road beyond the range, and the
    // plane it gives then names the fault (fit_ground_plane applies the range).
    std::vector<Eigen::Vector3f> points;
    std::size_t in_range = 0;
    const int w = disparity.width_px;
    const int h = disparity.height_px;
    const int first_row = std::max(0, static_cast<int>(std::ceil(camera.cy_px)));
    for (int v = first_row; v < h; v += 2) {
        const float* row = disparity.disparity_px.data() + static_cast<std::size_t>(v) * w;
        for (int u = 0; u < w; u += 4) {
            const double d = double{row[u]} - offset_px;
            if (!(row[u] > 0.0f) || !(d > 0.0)) continue;
            const double z = fb / d;
            in_range += z < options.ground_max_range_m ? 1 : 0;
            points.push_back(camera_point(camera, u, v, z).cast<float>());
        }
    }
    GroundOptions ransac;
    ransac.inlier_distance_m = options.ground_inlier_m;
    ransac.max_range_m = options.ground_max_range_m;
    ransac.min_inliers = std::max<std::size_t>(200, in_range / 10);
    auto plane = fit_ground_plane(points, ransac);
    if (!plane && in_range < points.size() / 2) {
        ransac.max_range_m = 1e6;
        ransac.min_inliers = std::max<std::size_t>(200, points.size() / 10);
        plane = fit_ground_plane(points, ransac);
    }
    if (!plane) {
        out.problem = "no level plane among the lower image's " + std::to_string(points.size()) +
                      " points (" + std::to_string(in_range) + " within " +
                      metres(options.ground_max_range_m) + ")" +
                      " (camera facing a wall, or no road in view?)";
        return out;
    }
    out.plane = *plane;
    out.camera_height_m = plane->camera_height_m();
    const Eigen::Vector3d& n = plane->normal;
    out.pitch_deg = std::asin(std::clamp(-n.z(), -1.0, 1.0)) * kDegPerRad;
    out.roll_deg = std::atan2(n.x(), -n.y()) * kDegPerRad;
    out.horizon_v_px = camera.cy_px - camera.fy_px * n.z() / n.y();
    if (out.camera_height_m < options.min_camera_height_m ||
        out.camera_height_m > options.max_camera_height_m) {
        out.problem = "the fitted road lies " + metres(out.camera_height_m) +
                      " below the camera, outside " + metres(options.min_camera_height_m) + " to " +
                      metres(options.max_camera_height_m) +
                      " (check the calibration's baseline and focal length)";
        return out;
    }
    out.found = true;
    return out;
}

}  // namespace cloud_analysis::geometry
