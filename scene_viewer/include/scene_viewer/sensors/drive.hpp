#pragma once

/// Synthetic drives: a scene whose thing entities move at constant velocity (the entity
/// format's 1.1 `velocity`), sampled at a frame rate, each frame with its ground truth (track
/// ids, positions, velocities, timestamps) as an entity file, and the drive's sequence index.

#include <string>

#include "scene_schema/entities.hpp"
#include "scene_schema/sequence.hpp"

namespace scene_viewer {

/// How a drive is sampled.
struct DriveOptions {
    int frames = 1;     ///< frames to render, >= 1
    double fps = 10.0;  ///< frame rate, Hz, > 0
    /// Throws std::invalid_argument naming the bad field (as the flag: --frames, --fps).
    void validate() const;
};

/// Name of frame i of a drive: ten digits, as KITTI raw's (0000000042).
std::string drive_frame_name(int index);

/// The scene at time t_s: every entity with a velocity moved by velocity * t_s (x and z), the
/// frame id set to `frame_name` and frame.timestamp to t_s; entities of thing classes (class
/// ids 24-33) without a track_id get their position among the file's entities as one, so the
/// truth of every frame names each object the same way.
scene_schema::EntityDocument scene_at(const scene_schema::EntityDocument& scene, double t_s,
                                      const std::string& frame_name);

/// The sequence index of a drive's truth files (truth/<frame>.json beside it).
scene_schema::SequenceIndex drive_index(const std::string& id, const DriveOptions& options);

}  // namespace scene_viewer
