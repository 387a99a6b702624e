#pragma once

/// Still objects placed in hindsight. A parked car first seen far away (where touching cars merge,
/// a car is cut where it is not, or it is lost in the stereo noise) is known well once the camera
/// has come near it; and as it does not move, its place in the drive's world is the same in the
/// frames before. A fixed-lag writer (track_files) therefore reports, in the frames it still
/// holds, every track that is still in the newest frame (its positions those of one still point,
/// StillHypothesis) wherever that frame's camera sees its place: a box of its class there becomes
/// the track's, at the track's place, or the track is added; and a box of another track on it (a
/// box that merges it with its neighbour, or a row's box sliding along with the camera) is no
/// object of its own. The frames' poses (frame.pose, `batch --odometry`) carry the place from
/// camera to camera; without poses the camera stands still.

#include <array>
#include <cstdint>
#include <optional>
#include <set>
#include <string>
#include <vector>

#include "cloud_analysis/tracking/tracker.hpp"
#include "scene_schema/entities.hpp"

namespace cloud_analysis::tracking {

/// A still object as a frame knows it, in that frame's camera.
struct StillObject {
    std::int64_t id = 0;  ///< its track
    std::string class_name;
    int class_id = 0;
    double confidence = 1.0;
    double x_m = 0.0, y_m = 0.0, z_m = 0.0;  ///< box centre
    double theta_rad = 0.0;
    double W = 1.0, H = 1.0, L = 1.0;  ///< held size, metres
};

/// What the newest frame knows: its still objects, the ids of its other confirmed tracks
/// (moving: their boxes are never taken over by a still object) and its pose.
struct Hindsight {
    std::vector<StillObject> still;
    std::set<std::int64_t> moving;
    std::optional<std::array<double, 12>> pose;
};

/// The tracker's state after its last frame (taken with `pose`): its still tracks (confirmed,
/// hit at least coast_min_hits times, StillHypothesis::consistent, the fitted velocity's std at
/// most still_max_speed_mps; placed at the fit's position) and its other confirmed ones.
Hindsight hindsight_of(const Tracker& tracker, const TrackerOptions& options,
                       const std::optional<std::array<double, 12>>& pose);

/// Reports in `frame` (an earlier frame) each still object of `known` it does not report yet,
/// where the object's footprint is in the frame's view (frame.frame.camera): the nearest entity
/// of the object's class on it (its centre on the object's footprint grown by support_margin_m,
/// or the object's centre on its footprint so grown) that no still object and no moving track
/// owns becomes the object's (track id, place, size, heading, zero velocity); otherwise the
/// object is added at its place, method "track hindsight". Then an entity of another track
/// (not a still one) of a still object's class on a still object the frame reports loses its
/// track id and velocity. Needs both poses or neither (a frame with one and not the other is
/// left alone). Returns the number of objects placed.
int place_still_objects(scene_schema::EntityDocument& frame, const Hindsight& known,
                        const TrackerOptions& options);

}  // namespace cloud_analysis::tracking
