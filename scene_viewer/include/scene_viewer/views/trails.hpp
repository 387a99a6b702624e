#pragma once

/// Track trails for playing a drive: each track's past positions, drawn as small flat markers
/// of its class colour behind the object (class "trail", which has no model, so it is a box).
/// When the frames carry poses (frame.pose: a moving camera) the positions are kept in the
/// drive's world and drawn where they lie as seen from the current camera, so a parked car's
/// trail is one spot and a moving car's is its path over the ground; the camera's own path is a
/// trail too (track kEgoTrack, class id kEgoClassId).

#include <cstdint>
#include <deque>
#include <map>
#include <vector>

#include "scene_schema/entities.hpp"
#include "scene_viewer/assets/model.hpp"

namespace scene_viewer {

/// The trail of the camera's own path.
inline constexpr std::int64_t kEgoTrack = -1;
/// Its class id and name: Cityscapes' "ego vehicle".
inline constexpr int kEgoClassId = 1;
inline constexpr const char* kEgoClassName = "ego vehicle";
/// The ground under the camera, metres below it (KITTI's mounting height), where its path is
/// drawn.
inline constexpr double kEgoGroundBelow_m = 1.65;

/// Past positions of the tracks, oldest first.
class TrailHistory {
  public:
    /// Keeps at most `length` positions per track (0: no trails).
    explicit TrailHistory(int length) : length_(length) {}
    /// Adds the positions of the tracked entities of a frame (after it was drawn).
    void remember(const scene_schema::EntityDocument& frame);
    /// Forgets everything (the tracker restarted).
    void clear() { points_.clear(); }
    /// The frame with one marker entity (`trail-<track>-<k>`, class "trail", the entity's class
    /// id, 0.35 x 0.04 x 0.35 m on the object's ground) per remembered position of its tracks.
    scene_schema::EntityDocument with_trails(const scene_schema::EntityDocument& frame) const;

  private:
    struct Point {
        double x, y_ground, z;
        int class_id;
    };
    int length_;
    std::map<std::int64_t, std::deque<Point>> points_;
};

/// Images side by side, top-aligned, on a black background (a strip of frames).
ImageRgba8 side_by_side(const std::vector<ImageRgba8>& images);

}  // namespace scene_viewer
