#pragma once

/// Camera views of a scene: the frame's own camera, a chase camera behind the ego car, a
/// top-down bird's-eye view and a free camera. Positions are given in the KITTI camera frame.

#include <optional>
#include <string>

#include <glm/glm.hpp>

#include "scene_schema/entities.hpp"

namespace scene_viewer {

enum class ViewKind { camera, chase, bev, free };

/// "camera", "chase", "bev", "free" -> ViewKind; throws std::invalid_argument otherwise.
ViewKind parse_view_kind(const std::string& name);
const char* to_string(ViewKind kind);

/// Everything a view needs; fields not used by a kind are ignored.
struct ViewSpec {
    ViewKind kind = ViewKind::camera;                          ///< which view
    std::optional<scene_schema::CameraIntrinsics> intrinsics;  ///< camera view: the frame's camera
    glm::vec3 eye_kitti{0.0f, -4.5f, -9.0f};                   ///< free/chase: eye, metres (KITTI)
    glm::vec3 target_kitti{0.0f, 0.5f, 12.0f};  ///< free/chase: look-at point, metres
    float fov_y_deg = 60.0f;                    ///< free/chase, and camera without
                                                ///< intrinsics: vertical field of view
    glm::vec2 bev_centre_xz{0.0f, 20.0f};       ///< bev: centre of the view, metres
    float bev_half_height_m = 30.0f;            ///< bev: half the forward extent, metres
    float near_m = 0.1f;                        ///< near plane, metres
    float far_m = 500.0f;                       ///< far plane, metres
    glm::vec3 camera_position_kitti{0.0f};      ///< camera view: optical centre in the
                                                ///< frame's left camera, metres (right
                                                ///< camera of a rig: (baseline, 0, 0))
    /// Throws std::invalid_argument naming the bad field.
    void validate() const;
};

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
