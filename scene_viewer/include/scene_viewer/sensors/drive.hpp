#pragma once

/// Synthetic drives: a scene whose thing entities move at constant velocity (the entity
/// format's 1.1 `velocity`), sampled at a frame rate, each frame with its ground truth (track
/// ids, positions, velocities, timestamps) as an entity file, and the drive's sequence index.

#include <array>
#include <string>
#include <vector>

#include "scene_schema/entities.hpp"
#include "scene_schema/sequence.hpp"

namespace scene_viewer {

/// The camera's own motion over a drive: a unicycle on the road plane at constant speed and yaw
/// rate, starting at the scene's camera. KITTI camera axes (x right, y down, z forward); a
/// positive yaw rate turns right (towards +x), on a circle of radius speed / yaw rate.
struct EgoMotion {
    double speed_mps = 0.0;     ///< along the camera's heading, m/s
    double yaw_rate_dps = 0.0;  ///< degrees a second, + turns right
    /// True when the camera moves or turns.
    bool moving() const { return speed_mps != 0.0 || yaw_rate_dps != 0.0; }
    /// T_world_camera at time t_s, the row-major 3x4 [R | t] of KITTI odometry poses (the
    /// world: the camera at t = 0): R turns by yaw_rate * t about +y, t is on the circle.
    std::array<double, 12> pose_at(double t_s) const;
};

/// How a drive is sampled.
struct DriveOptions {
    int frames = 1;     ///< frames to render, >= 1
    double fps = 10.0;  ///< frame rate, Hz, > 0
    EgoMotion ego;      ///< the camera's motion (still by default)
    /// Throws std::invalid_argument naming the bad field (as the flag: --frames, --fps).
    void validate() const;
};

/// Name of frame i of a drive: ten digits, as KITTI raw's (0000000042).
std::string drive_frame_name(int index);

/// The scene at time t_s: every entity with a velocity moved by velocity * t_s (x and z), the
/// frame id set to `frame_name` and frame.timestamp to t_s; entities of thing classes (class
/// ids 24-33) without a track_id get their position among the file's entities as one, so the
/// truth of every frame names each object the same way. With a moving camera the scene is the
/// world (the camera at t = 0): every entity is then seen from the camera at t_s (position,
/// heading and its over-the-ground velocity turned into that camera's axes) and frame.pose is
/// the camera's pose.
scene_schema::EntityDocument scene_at(const scene_schema::EntityDocument& scene, double t_s,
                                      const std::string& frame_name, const EgoMotion& ego = {});

/// The sequence index of a drive's truth files (truth/<frame>.json beside it).
scene_schema::SequenceIndex drive_index(const std::string& id, const DriveOptions& options);

}  // namespace scene_viewer
