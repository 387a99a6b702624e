#include "scene_viewer/ecs/coordinates.hpp"

#include <cmath>

#include <glm/gtc/matrix_transform.hpp>
#include "stereoscene/support/angles.hpp"

using stereoscene::support::kPi;

namespace scene_viewer {

glm::mat4 gl_from_kitti() {
    glm::mat4 m(1.0f);
    m[1][1] = -1.0f;
    m[2][2] = -1.0f;
    return m;
}

glm::vec3 kitti_to_gl(const glm::vec3& p_kitti) {
    return glm::vec3(gl_from_kitti() * glm::vec4(p_kitti, 1.0f));
}

glm::vec3 heading_kitti(double theta_rad) {
    return {static_cast<float>(std::cos(theta_rad)), 0.0f,
            static_cast<float>(-std::sin(theta_rad))};
}

float gl_yaw_from_kitti_theta(double theta_rad) {
    // Ry(phi) maps +Z to (sin phi, 0, cos phi); the heading in GL is (cos theta, 0, sin theta).
    return static_cast<float>(kPi / 2.0 - theta_rad);
}

glm::mat4 fit_bounds_to_unit_cube(const glm::vec3& bounds_min, const glm::vec3& bounds_max) {
    const glm::vec3 extent = bounds_max - bounds_min;
    glm::vec3 scale(1.0f);
    for (int i = 0; i < 3; ++i) {
        if (extent[i] > 1e-9f) scale[i] = 1.0f / extent[i];
    }
    const glm::vec3 centre = 0.5f * (bounds_min + bounds_max);
    return glm::translate(glm::scale(glm::mat4(1.0f), scale), -centre);
}

glm::mat4 box_world_matrix(const glm::vec3& centre_kitti, double theta_rad,
                           const glm::vec3& whl_m) {
    glm::mat4 m = glm::translate(glm::mat4(1.0f), kitti_to_gl(centre_kitti));
    m = glm::rotate(m, gl_yaw_from_kitti_theta(theta_rad), glm::vec3(0.0f, 1.0f, 0.0f));
    return glm::scale(m, whl_m);
}

glm::dmat4 kitti_pose_matrix(const std::array<double, 12>& T) {
    glm::dmat4 m(1.0);  // column-major: m[column][row]
    for (std::size_t r = 0; r < 3; ++r)
        for (std::size_t c = 0; c < 4; ++c) m[c][r] = T[4 * r + c];
    return m;
}

}  // namespace scene_viewer
