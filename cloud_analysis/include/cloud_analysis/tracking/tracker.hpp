#pragma once

/// Multi-object tracking over a drive's entity documents: one constant-velocity Kalman filter
/// per object in the ground plane, Hungarian assignment on bird's-eye centre distance gated
/// per class, birth after N hits and death after M misses (AB3DMOT, Weng et al. 2020, with
/// distance instead of 3D IoU), smoothed size and heading.

#include <array>
#include <cstdint>
#include <deque>
#include <map>
#include <optional>
#include <string>
#include <vector>

#include "cloud_analysis/tracking/kalman.hpp"
#include "scene_schema/entities.hpp"

namespace cloud_analysis::tracking {

/// How objects are followed from frame to frame.
struct TrackerOptions {
    /// Classes that get tracks; other entities (road, building...) pass through untouched.
    std::vector<std::string> classes{"car",   "truck",   "bus",       "person",
                                     "rider", "bicycle", "motorcycle"};
    /// Gate per class: a detection farther than this from a track's predicted centre (bird's
    /// eye, metres) is not that track's. Classes not listed use default_gate_m.
    std::map<std::string, double> gate_m{
        {"car", 2.5}, {"truck", 3.0}, {"bus", 3.0}, {"person", 1.2}, {"rider", 1.5}};
    double default_gate_m = 2.0;  ///< gate of classes without their own, metres
    /// Statistical gate: a detection whose squared Mahalanobis distance from a track's
    /// prediction (its covariance plus the measurement's, GroundKalman::mahalanobis2) exceeds
    /// this is not that track's. 9.21 keeps 99 % of true matches (chi-square, 2 degrees of
    /// freedom); 0 turns it off.
    double gate_chi2 = 9.21;
    int min_hits = 3;  ///< a track is confirmed (reported) after this many hits
    /// Tracks born in the first min_hits frames of a run are confirmed at once (AB3DMOT's
    /// rule: nothing is lost at the start, but their heading is then reported before their
    /// motion can tell which way round the box is).
    bool confirm_first_frames = true;
    int max_misses = 10;  ///< a confirmed track dies after this many frames in a row without a hit
    double max_gap_s = 1.0;  ///< a longer gap between frames restarts the tracker, s
    /// A confirmed track missed in a frame is still reported, at its prediction, for this many
    /// frames in a row (the detector losing a car for a frame or two, e.g. behind a passing
    /// car); 0 reports only matched tracks. A prediction wholly outside the frame's camera
    /// view (frame.camera: no corner of its footprint in front of it and within its image's
    /// columns) is not reported: the object left the image.
    int coast_frames = 2;
    /// Only a track hit at least this often coasts: one confirmed on a few stray boxes and
    /// lost at once is more likely a stray than a car the detector missed. 0 coasts every
    /// confirmed track.
    int coast_min_hits = 6;
    /// A still track (confirmed, hit at least coast_min_hits times, its velocity known and
    /// under still_max_speed_mps) missed in a frame while an entity of a support class has its
    /// centre on the track's footprint (its box grown by support_margin_m on every side) is seen
    /// in part there, not missed: a parked car behind a passing one shows through the gaps as
    /// pieces the stereo-only rules call static, wall or person. It is reported at its
    /// prediction for up to support_frames such frames in a row; 0 turns this off.
    int support_frames = 10;
    /// Under this speed a track is still (support_frames); a still object placed in hindsight
    /// (hindsight.hpp) must have its fitted velocity known to this std as well, m/s.
    double still_max_speed_mps = 0.5;
    double support_margin_m = 0.5;  ///< see support_frames, metres
    std::vector<std::string> support_classes{"car",   "truck",   "bus",        "person",
                                             "rider", "bicycle", "motorcycle", "static",
                                             "wall",  "fence",   "pole"};
    double heading_gain = 0.3;  ///< weight of a new heading in the smoothed one, 0..1
    double height_gain = 0.3;   ///< weight of a new box centre height (y), 0..1
    /// Above this speed the heading follows the velocity's direction (resolving the box's
    /// 180 degree ambiguity); below it the box's heading is kept, aligned modulo pi, m/s.
    double heading_from_motion_mps = 2.0;
    /// After confirmation the size is held; during the next size_settle_hits hits it is
    /// re-estimated (mean of the measurements since) when that mean leaves it by more than
    /// this in W, H or L (a car first seen truncated), metres; afterwards it is fixed.
    double size_relock_m = 0.4;
    int size_settle_hits = 0;  ///< hits after confirmation during which the size may change
    /// The velocity is written only once the filter knows it this well (std of vx and vz,
    /// m/s); before, the entity has no `velocity` (unknown, not 0).
    double max_velocity_sigma_mps = 1.0;
    /// Frames of each track's filter steps kept for Tracker::smoothed (a fixed-lag writer's
    /// lag plus one); 0 keeps none.
    int history_frames = 0;
    KalmanOptions kalman;  ///< motion model noise
    /// Throws std::invalid_argument naming the bad field.
    void validate() const;
};

/// A track confirmed in a frame, and what it was before (TrackerFrameStats::confirmed).
struct ConfirmedTrack {
    std::int64_t id = 0;
    /// Its detections' entity ids in the frames before this one, oldest first, one a frame, the
    /// last in the frame just before.
    std::vector<std::string> earlier_entity_ids;
    scene_schema::Entity reported;  ///< its entity in this frame
};

/// What one frame gave the tracker.
struct TrackerFrameStats {
    int detections = 0;      ///< entities of tracked classes
    int matched = 0;         ///< of those, associated with an existing track
    int born = 0;            ///< new tracks
    int died = 0;            ///< tracks removed after too many misses
    int reported = 0;        ///< entities written with a track_id
    int coasted = 0;         ///< of those, predictions of tracks missed in this frame
    bool restarted = false;  ///< the tracker dropped every track first (gap or time going back)
    /// Tracks whose heading the direction of motion turned round by pi in this frame (a box
    /// reported facing backwards before its velocity was known); a fixed-lag writer turns
    /// their entities in the frames it still holds.
    std::vector<std::int64_t> turned;
    /// Tracks confirmed in this frame after earlier hits (not born confirmed): each with the ids
    /// of the entities it was made of in the frames before, oldest first, and its box as
    /// reported now; a fixed-lag writer reports it in the frames it still holds too.
    std::vector<ConfirmedTrack> confirmed;
};

/// One followed object.
struct Track {
    std::int64_t id = 0;               ///< the track_id written
    std::string class_name;            ///< class of its first detection
    int class_id = 0;                  ///< its class id
    double confidence = 1.0;           ///< of its last detection
    GroundKalman motion;               ///< position and velocity in the ground plane
    StillHypothesis still;             ///< its hits as those of one still point (hindsight)
    double y_m = 0.0;                  ///< smoothed box centre height (camera y), metres
    double theta_rad = 0.0;            ///< smoothed heading
    double W = 1.0, H = 1.0, L = 1.0;  ///< held (or running mean) size, metres
    double sum_W = 0.0, sum_H = 0.0, sum_L = 0.0;  ///< sizes measured since the last lock
    int size_samples = 0;                          ///< measurements in the sums
    bool size_locked = false;                      ///< the size is held (after confirmation)
    int hits_since_lock = 0;                       ///< hits since the size was first held
    int hits = 0;                                  ///< frames with a detection
    int misses = 0;                                ///< consecutive frames without one
    int seen_in_part = 0;    ///< frames missed but seen in part since its last hit
    bool confirmed = false;  ///< reached min_hits (or was born in the first frames)
    /// Before confirmation: the entity ids of its hits, oldest first, one a frame.
    std::vector<std::string> tentative_entity_ids{};
};

/// How the ground plane moves from one camera of a drive into another: a point's (x, z) in the
/// first camera is (R (x, z) + t) in the second, its y grows by dy and headings by yaw_rad (a
/// car's camera pitches and rolls little, so only the yaw about +y is kept).
struct GroundMotion {
    double yaw_rad = 0.0;
    Eigen::Matrix2d R = Eigen::Matrix2d::Identity();
    Eigen::Vector2d t = Eigen::Vector2d::Zero();
    double dy_m = 0.0;
};

/// The ground motion from camera `T_world_from` into camera `T_world_to` (both T_world_camera,
/// row-major 3x4, frame.pose).
GroundMotion ground_motion(const std::array<double, 12>& T_world_from,
                           const std::array<double, 12>& T_world_to);

/// Whether a track is a still object: confirmed, hit at least coast_min_hits times, its
/// velocity known (std at most max_velocity_sigma_mps) and under still_max_speed_mps.
bool is_still(const Track& t, const TrackerOptions& o);

/// The id of an entity a track adds to `frame` (a prediction, a still object in hindsight):
/// "track-<id>", or "track-<id>-<k>" with the smallest k >= 2 that `frame` does not use yet.
std::string track_entity_id(std::int64_t track_id, const scene_schema::EntityDocument& frame);

/// Whether (x, z) lies on the footprint of a box (centre cx, cz, heading, length, width) grown
/// by `margin_m` on every side.
bool on_footprint(double x_m, double z_m, double cx_m, double cz_m, double theta_rad, double L_m,
                  double W_m, double margin_m);

/// Whether any corner of a footprint (centre x, z, heading, length, width, in `camera`'s
/// coordinates) lies in front of the camera and within its image's columns. Without a camera,
/// in view.
bool footprint_in_view(double x_m, double z_m, double theta_rad, double L_m, double W_m,
                       const std::optional<scene_schema::CameraIntrinsics>& camera);

/// The tracker's state across frames. Feed frames in capture order.
class Tracker {
  public:
    explicit Tracker(TrackerOptions options = {});

    /// Tracks one frame taken at `timestamp_s`: returns the document with `track_id`,
    /// `velocity` and smoothed position, size and heading on the entities of confirmed tracks
    /// matched in this frame; other entities are kept as they came. When this frame and the
    /// one before carry a pose (frame.pose, the camera's in the drive's world), the tracks are
    /// first carried into this frame's camera by the camera's motion between them: positions
    /// stay in each frame's camera coordinates, velocities are over the ground (a parked car
    /// is still however the camera moves). A timestamp not after the
    /// previous one, or more than max_gap_s after it, restarts the tracker (new ids, never
    /// reused); `stats` (optional) says what happened.
    scene_schema::EntityDocument update(const scene_schema::EntityDocument& frame,
                                        double timestamp_s, TrackerFrameStats* stats = nullptr);

    /// Drops every track (the next ids still count up).
    void reset();

    /// Live tracks (confirmed or not).
    const std::vector<Track>& tracks() const { return tracks_; }

    /// The tracker's settings.
    const TrackerOptions& options() const { return options_; }

    /// The pose of the last frame update() took (frame.pose), when it had one.
    const std::optional<std::array<double, 12>>& last_pose() const { return last_pose_; }

    /// The number of the last frame update() took (1 for the first; restarts keep counting).
    std::int64_t frame_number() const { return frame_number_; }

    /// Track `id`'s state (x, z, vx, vz) in frame `frame` (that frame's camera) given every
    /// frame since, up to the last one (fixed-lag Rauch-Tung-Striebel smoothing over the
    /// TrackerOptions::history_frames kept); none when the frame is not kept for it.
    std::optional<Eigen::Vector4d> smoothed(std::int64_t id, std::int64_t frame) const;

  private:
    void predict(double dt_s);
    /// Carries every track from the previous frame's camera into this frame's.
    void carry(const std::array<double, 12>& T_world_prev,
               const std::array<double, 12>& T_world_curr);
    void associate(const scene_schema::EntityDocument& frame, std::vector<int>& track_of);
    /// The time since the last frame, seconds (0 after a restart: a gap or a step back).
    double advance_clock(double timestamp_s, TrackerFrameStats& s);
    /// Updates the matched tracks, starts tracks for the rest, reports the confirmed ones.
    void take_detections(const scene_schema::EntityDocument& frame, std::vector<int>& track_of,
                         std::vector<char>& hit, scene_schema::EntityDocument& out,
                         TrackerFrameStats& s);
    /// Counts the misses, drops dead tracks, reports coasting ones at their prediction.
    void age_tracks(const scene_schema::EntityDocument& frame, const std::vector<int>& track_of,
                    const std::vector<char>& hit, scene_schema::EntityDocument& out,
                    TrackerFrameStats& s);
    /// Keeps this frame's filter step of every track (history_frames > 0).
    void record_steps();
    TrackerOptions options_;
    std::vector<Track> tracks_;
    std::optional<double> last_time_s_;
    std::optional<std::array<double, 12>> last_pose_;  ///< the previous frame's, when it had one
    std::int64_t next_id_ = 0;
    int frames_since_start_ = 0;
    std::int64_t frame_number_ = 0;
    /// A track's last filter steps, one a frame, the newest taken in frame last_frame.
    struct History {
        std::deque<KalmanStep> steps;
        std::int64_t last_frame = 0;
    };
    std::map<std::int64_t, History> histories_;  ///< by track id, dead tracks' kept a while
};

/// Tracks a whole drive (frames in order, one timestamp each).
std::vector<scene_schema::EntityDocument> track_sequence(
    const std::vector<scene_schema::EntityDocument>& frames, const std::vector<double>& times_s,
    const TrackerOptions& options);

}  // namespace cloud_analysis::tracking
