#pragma once

/// Frame conventions of the renderer. Entity files use the KITTI rectified left camera frame
/// (x right, y down, z forward, metres); the renderer's world is the OpenGL camera frame of that
/// same camera (x right, y up, z backward). The conversion happens here and nowhere else.

#include <array>

#include <glm/glm.hpp>

namespace scene_viewer {

/// The one frame conversion: KITTI camera (x right, y down, z forward) -> OpenGL (x right, y up,
/// z backward). A rotation by pi about x, i.e. diag(1, -1, -1).
glm::mat4 gl_from_kitti();

/// A KITTI camera-frame point expressed in the OpenGL world frame.
glm::vec3 kitti_to_gl(const glm::vec3& p_kitti);

/// Unit heading (length axis) of an entity in the KITTI frame: (cos theta, 0, -sin theta).
glm::vec3 heading_kitti(double theta_rad);

/// Rotation about the OpenGL +y axis that turns a glTF model's front (+Z) onto the heading of an
/// entity with KITTI yaw theta: pi/2 - theta.
float gl_yaw_from_kitti_theta(double theta_rad);

/// Maps a model's axis-aligned bounds onto the unit cube [-0.5, 0.5]^3 (centre, then scale each
/// axis by 1 / extent; a flat axis keeps scale 1).
glm::mat4 fit_bounds_to_unit_cube(const glm::vec3& bounds_min, const glm::vec3& bounds_max);

/// A drive's pose (frame.pose: the row-major 3x4 [R | t] of T_world_camera, KITTI frames) as a
/// 4x4 matrix: camera-frame points to the drive's world, both in KITTI axes.
glm::dmat4 kitti_pose_matrix(const std::array<double, 12>& T_world_camera);

/// World matrix of an upright box: translate to the centre (KITTI metres), yaw (KITTI theta),
/// scale the unit cube to W (x), H (y), L (z). The result maps model-frame points into the GL
/// world frame.
glm::mat4 box_world_matrix(const glm::vec3& centre_kitti, double theta_rad, const glm::vec3& whl_m);

}  // namespace scene_viewer
