#pragma once

/// What a camera looks at: the kind of view and its parameters, the data of the Camera
/// component. The matrices are computed from it in views/views.hpp.

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

}  // namespace scene_viewer
