#pragma once

/// Camera views of a scene: the frame's own camera, a chase camera behind the ego car, a
/// top-down bird's-eye view and a free camera. Positions are given in the KITTI camera frame.

#include <optional>
#include <string>

#include <glm/glm.hpp>

#include "scene_schema/entities.hpp"
#include "scene_viewer/ecs/view_spec.hpp"

namespace scene_viewer {

/// View and projection matrices of a view for a target of width x height pixels; the view
/// matrix maps the OpenGL world frame (see coordinates.hpp) to eye space.
struct ViewMatrices {
    glm::mat4 view{1.0f};
    glm::mat4 projection{1.0f};
};

ViewMatrices view_matrices(const ViewSpec& spec, int width_px, int height_px);

/// OpenGL projection of a pinhole camera (fx, fy, cx, cy in pixels of a width x height image,
/// row 0 at the top) rendered at target_width x target_height; a point projects onto the same
/// relative pixel position as in the source image.
glm::mat4 projection_from_intrinsics(const scene_schema::CameraIntrinsics& k, int target_width,
                                     int target_height, float near_m, float far_m);

/// The chase view's defaults: behind and above the ego car, looking forward.
ViewSpec chase_view();

/// A bird's-eye view that frames every entity footprint (and the ego position) with a margin.
ViewSpec bev_view_fitting(const scene_schema::EntityDocument& document, float aspect);

}  // namespace scene_viewer
