#include "scene_viewer/views/views.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include <glm/gtc/matrix_transform.hpp>

#include "scene_viewer/ecs/coordinates.hpp"

namespace scene_viewer {

glm::mat4 projection_from_intrinsics(const scene_schema::CameraIntrinsics& k, int target_width,
                                     int target_height, float near_m, float far_m) {
    // Scale the intrinsics to the target size, then build the GL frustum whose NDC x, y equal the
    // pinhole projection u = fx X/Z + cx, v = fy Y/Z + cy (v downwards) mapped to [-1, 1].
    const double sx = static_cast<double>(target_width) / k.width_px;
    const double sy = static_cast<double>(target_height) / k.height_px;
    const double fx = k.fx_px * sx, fy = k.fy_px * sy, cx = k.cx_px * sx, cy = k.cy_px * sy;
    const double w = target_width, h = target_height;
    glm::mat4 p(0.0f);
    p[0][0] = static_cast<float>(2.0 * fx / w);
    p[1][1] = static_cast<float>(2.0 * fy / h);
    p[2][0] = static_cast<float>(1.0 - 2.0 * cx / w);
    p[2][1] = static_cast<float>(2.0 * cy / h - 1.0);
    p[2][2] = -(far_m + near_m) / (far_m - near_m);
    p[2][3] = -1.0f;
    p[3][2] = -2.0f * far_m * near_m / (far_m - near_m);
    return p;
}

namespace {

glm::mat4 look_at_kitti(const glm::vec3& eye_kitti, const glm::vec3& target_kitti) {
    const glm::vec3 eye = kitti_to_gl(eye_kitti);
    const glm::vec3 target = kitti_to_gl(target_kitti);
    const glm::vec3 dir = glm::normalize(target - eye);
    // Straight down (or up) has no horizon: then "forward" (-z in GL) is up in the image.
    const glm::vec3 up = std::abs(dir.y) > 0.999f ? glm::vec3(0, 0, -1) : glm::vec3(0, 1, 0);
    return glm::lookAt(eye, target, up);
}

}  // namespace

ViewMatrices view_matrices(const ViewSpec& spec, int width_px, int height_px) {
    spec.validate();
    const float aspect = static_cast<float>(width_px) / static_cast<float>(height_px);
    ViewMatrices m;
    switch (spec.kind) {
        case ViewKind::camera:
            // The renderer's world frame is the GL frame of the left camera: identity pose, or a
            // pure translation for another camera of a rectified rig.
            m.view = glm::translate(glm::mat4(1.0f), -kitti_to_gl(spec.camera_position_kitti));
            m.projection = spec.intrinsics
                               ? projection_from_intrinsics(*spec.intrinsics, width_px, height_px,
                                                            spec.near_m, spec.far_m)
                               : glm::perspective(glm::radians(spec.fov_y_deg), aspect, spec.near_m,
                                                  spec.far_m);
            break;
        case ViewKind::chase:
        case ViewKind::free:
            m.view = look_at_kitti(spec.eye_kitti, spec.target_kitti);
            m.projection =
                glm::perspective(glm::radians(spec.fov_y_deg), aspect, spec.near_m, spec.far_m);
            break;
        case ViewKind::bev: {
            const float height_m = 200.0f;  // eye above the ground, metres
            const glm::vec3 target(spec.bev_centre_xz.x, 0.0f, spec.bev_centre_xz.y);
            m.view = look_at_kitti(target + glm::vec3(0.0f, -height_m, 0.0f), target);
            const float hh = spec.bev_half_height_m;
            const float hw = hh * aspect;
            m.projection = glm::ortho(-hw, hw, -hh, hh, 1.0f, 2.0f * height_m);
            break;
        }
    }
    return m;
}

ViewSpec chase_view() {
    ViewSpec v;
    v.kind = ViewKind::chase;
    v.eye_kitti = {0.0f, -4.5f, -11.0f};
    v.target_kitti = {0.0f, 0.5f, 12.0f};
    v.fov_y_deg = 55.0f;
    return v;
}

ViewSpec bev_view_fitting(const scene_schema::EntityDocument& document, float aspect) {
    // Footprint bounds in (x, z), starting from the ego position so the camera stays in view.
    float min_x = -2.0f, max_x = 2.0f, min_z = -4.0f, max_z = 4.0f;
    for (const auto& e : document.entities) {
        const float r = 0.5f * static_cast<float>(std::hypot(e.W, e.L));
        min_x = std::min(min_x, static_cast<float>(e.x) - r);
        max_x = std::max(max_x, static_cast<float>(e.x) + r);
        min_z = std::min(min_z, static_cast<float>(e.z) - r);
        max_z = std::max(max_z, static_cast<float>(e.z) + r);
    }
    ViewSpec v;
    v.kind = ViewKind::bev;
    v.bev_centre_xz = {0.5f * (min_x + max_x), 0.5f * (min_z + max_z)};
    const float half_h = 0.5f * (max_z - min_z);
    const float half_w = 0.5f * (max_x - min_x);
    v.bev_half_height_m = 1.05f * std::max(half_h, half_w / aspect);
    return v;
}

}  // namespace scene_viewer
