#include "cloud_analysis/tracking/tracker.hpp"
#include "cloud_analysis/support/box_axes.hpp"

#include <algorithm>
#include <cmath>
#include <iterator>
#include <stdexcept>

#include <Eigen/LU>

#include "cloud_analysis/tracking/assignment.hpp"
#include "stereoscene/support/angles.hpp"

using stereoscene::support::wrap_angle;

namespace cloud_analysis::tracking {

namespace {

using stereoscene::support::kPi;

/// a or a + pi, whichever is nearer to `reference` (a box's heading is only known modulo pi).
double align_modulo_pi(double a, double reference) {
    const double d = wrap_angle(a - reference);
    return std::abs(d) > kPi / 2.0 ? wrap_angle(a + kPi) : wrap_angle(a);
}

bool in(const std::vector<std::string>& list, const std::string& name) {
    return std::find(list.begin(), list.end(), name) != list.end();
}

void require(bool ok, const char* field, const char* rule) {
    if (!ok) throw std::invalid_argument(std::string(field) + " " + rule);
}

}  // namespace

void TrackerOptions::validate() const {
    require(std::isfinite(default_gate_m) && default_gate_m > 0.0, "default_gate_m", "must be > 0");
    for (const auto& [name, gate] : gate_m) {
        if (!(std::isfinite(gate) && gate > 0.0)) {
            throw std::invalid_argument("gate_m[" + name + "] must be > 0");
        }
    }
    require(std::isfinite(gate_chi2) && gate_chi2 >= 0.0, "gate_chi2", "must be >= 0");
    require(min_hits >= 1, "min_hits", "must be >= 1");
    require(max_misses >= 1, "max_misses", "must be >= 1");
    require(std::isfinite(max_gap_s) && max_gap_s > 0.0, "max_gap_s", "must be > 0");
    require(coast_frames >= 0 && coast_frames <= 100, "coast_frames", "must be in 0..100");
    require(coast_min_hits >= 0, "coast_min_hits", "must be >= 0");
    require(support_frames >= 0 && support_frames <= 1000, "support_frames", "must be in 0..1000");
    require(std::isfinite(still_max_speed_mps) && still_max_speed_mps >= 0.0, "still_max_speed_mps",
            "must be >= 0");
    require(std::isfinite(support_margin_m) && support_margin_m >= 0.0, "support_margin_m",
            "must be >= 0");
    require(heading_gain > 0.0 && heading_gain <= 1.0, "heading_gain", "must be in (0, 1]");
    require(height_gain > 0.0 && height_gain <= 1.0, "height_gain", "must be in (0, 1]");
    require(std::isfinite(heading_from_motion_mps) && heading_from_motion_mps >= 0.0,
            "heading_from_motion_mps", "must be >= 0");
    require(std::isfinite(size_relock_m) && size_relock_m >= 0.0, "size_relock_m", "must be >= 0");
    require(size_settle_hits >= 0, "size_settle_hits", "must be >= 0");
    require(std::isfinite(max_velocity_sigma_mps) && max_velocity_sigma_mps > 0.0,
            "max_velocity_sigma_mps", "must be > 0");
    require(history_frames >= 0 && history_frames <= 1001, "history_frames", "must be in 0..1001");
    kalman.validate();
}

Tracker::Tracker(TrackerOptions options) : options_(std::move(options)) { options_.validate(); }

GroundMotion ground_motion(const std::array<double, 12>& T_world_from,
                           const std::array<double, 12>& T_world_to) {
    const auto matrix = [](const std::array<double, 12>& a) {
        Eigen::Matrix4d T = Eigen::Matrix4d::Identity();
        for (int k = 0; k < 12; ++k) T(k / 4, k % 4) = a[static_cast<std::size_t>(k)];
        return T;
    };
    const Eigen::Matrix4d T_to_from = matrix(T_world_to).inverse() * matrix(T_world_from);
    GroundMotion m;
    m.yaw_rad = std::atan2(T_to_from(0, 2), T_to_from(0, 0));
    m.R << std::cos(m.yaw_rad), std::sin(m.yaw_rad), -std::sin(m.yaw_rad), std::cos(m.yaw_rad);
    m.t = Eigen::Vector2d(T_to_from(0, 3), T_to_from(2, 3));
    m.dy_m = T_to_from(1, 3);
    return m;
}

void Tracker::carry(const std::array<double, 12>& T_world_prev,
                    const std::array<double, 12>& T_world_curr) {
    const GroundMotion m = ground_motion(T_world_prev, T_world_curr);
    for (Track& track : tracks_) {
        track.motion.change_frame(m.R, m.t);
        track.still.change_frame(m.R, m.t);
        track.theta_rad += m.yaw_rad;
        track.y_m += m.dy_m;
    }
}

void Tracker::reset() {
    tracks_.clear();
    last_time_s_.reset();
    last_pose_.reset();
    frames_since_start_ = 0;
}

void Tracker::predict(double dt_s) {
    for (Track& t : tracks_) {
        t.motion.predict(dt_s);
        t.still.predict(dt_s);
    }
}

void Tracker::associate(const scene_schema::EntityDocument& frame, std::vector<int>& track_of) {
    std::vector<int> detections;
    for (std::size_t i = 0; i < frame.entities.size(); ++i) {
        if (in(options_.classes, frame.entities[i].class_name)) {
            detections.push_back(static_cast<int>(i));
        }
    }
    CostMatrix costs;
    costs.rows = static_cast<int>(tracks_.size());
    costs.cols = static_cast<int>(detections.size());
    costs.cost.resize(static_cast<std::size_t>(costs.rows) * costs.cols);
    // Cost: bird's-eye centre distance over the class's gate, so one gate of 1 serves all; a
    // detection outside the track's statistical gate (its prediction's covariance plus the
    // stereo measurement's, long along the viewing ray) is not the track's either.
    for (int r = 0; r < costs.rows; ++r) {
        const Track& t = tracks_[r];
        const auto gate = options_.gate_m.find(t.class_name);
        const double gate_m =
            gate == options_.gate_m.end() ? options_.default_gate_m : gate->second;
        for (int c = 0; c < costs.cols; ++c) {
            const auto& e = frame.entities[detections[c]];
            const double d = std::hypot(e.x - t.motion.x_m(), e.z - t.motion.z_m());
            const bool inside =
                options_.gate_chi2 <= 0.0 || t.motion.mahalanobis2(e.x, e.z) <= options_.gate_chi2;
            costs.cost[static_cast<std::size_t>(r) * costs.cols + c] =
                e.class_name == t.class_name && inside ? d / gate_m : 2.0;
        }
    }
    track_of.assign(frame.entities.size(), -2);  // -2: not a tracked class
    for (int d : detections) track_of[d] = -1;   // -1: not matched yet
    // Confirmed tracks first, then tentative ones with the detections left (the matching
    // cascade of DeepSORT, Wojke et al. 2017): a track born on a stray box two frames ago
    // never takes the detection of a car followed for seconds.
    std::vector<char> taken(static_cast<std::size_t>(costs.cols), 0);
    for (const bool confirmed : {true, false}) {
        CostMatrix stage = costs;
        for (int r = 0; r < costs.rows; ++r) {
            for (int c = 0; c < costs.cols; ++c) {
                if (tracks_[r].confirmed != confirmed || taken[c]) {
                    stage.cost[static_cast<std::size_t>(r) * costs.cols + c] = 2.0;
                }
            }
        }
        for (const Match& m : assign(stage, 1.0)) {
            track_of[detections[m.col]] = m.row;
            taken[m.col] = 1;
        }
    }
}

namespace {

/// Whether a track's velocity is known well enough to be reported (std of vx and vz at most
/// max_velocity_sigma_mps).
bool velocity_known(const Track& t, const TrackerOptions& o) {
    const auto& P = t.motion.covariance();
    const double v2 = o.max_velocity_sigma_mps * o.max_velocity_sigma_mps;
    return P(2, 2) <= v2 && P(3, 3) <= v2;
}

/// Folds a measured box into a matched track's height, heading and size; true when the
/// direction of motion turned the track's heading round.
bool absorb(Track& t, const scene_schema::Entity& e, const TrackerOptions& o) {
    t.y_m += o.height_gain * (e.y - t.y_m);
    bool turned = false;
    double target = align_modulo_pi(e.theta, t.theta_rad);
    const double speed = std::hypot(t.motion.vx_mps(), t.motion.vz_mps());
    // Only a velocity known well enough to be reported may turn the heading: a track's first
    // velocities are differences of two boxes, whose jitter alone can pass the speed.
    if (speed > o.heading_from_motion_mps && velocity_known(t, o)) {
        // Moving: the box's axis, turned to point where the object goes.
        const double motion = std::atan2(-t.motion.vz_mps(), t.motion.vx_mps());
        target = align_modulo_pi(target, motion);
        // A track born facing backwards turns round at once, not through a half turn.
        if (std::abs(wrap_angle(t.theta_rad - motion)) > kPi / 2.0) {
            t.theta_rad = wrap_angle(t.theta_rad + kPi);
            turned = true;
        }
    }
    t.theta_rad = wrap_angle(t.theta_rad + o.heading_gain * wrap_angle(target - t.theta_rad));
    t.sum_W += e.W;
    t.sum_H += e.H;
    t.sum_L += e.L;
    ++t.size_samples;
    const double n = t.size_samples;
    const double W = t.sum_W / n, H = t.sum_H / n, L = t.sum_L / n;
    if (t.size_locked) ++t.hits_since_lock;
    if (!t.size_locked) {
        t.W = W;
        t.H = H;
        t.L = L;
    } else if (t.hits_since_lock <= o.size_settle_hits &&
               std::max({std::abs(W - t.W), std::abs(H - t.H), std::abs(L - t.L)}) >
                   o.size_relock_m) {
        t.W = W;
        t.H = H;
        t.L = L;
        t.sum_W = t.sum_H = t.sum_L = 0.0;
        t.size_samples = 0;
    }
    return turned;
}

Track born(const scene_schema::Entity& e, std::int64_t id, const TrackerOptions& o) {
    Track t{id,
            e.class_name,
            e.class_id,
            e.confidence,
            GroundKalman(e.x, e.z, o.kalman),
            StillHypothesis(e.x, e.z, o.kalman)};
    t.y_m = e.y;
    t.theta_rad = wrap_angle(e.theta);
    t.W = t.sum_W = e.W;
    t.H = t.sum_H = e.H;
    t.L = t.sum_L = e.L;
    t.size_samples = 1;
    t.hits = 1;
    return t;
}

void report(const Track& t, const TrackerOptions& o, scene_schema::Entity& e) {
    e.track_id = t.id;
    if (velocity_known(t, o)) {
        e.velocity = scene_schema::Velocity{t.motion.vx_mps(), t.motion.vz_mps()};
    } else {
        e.velocity.reset();
    }
    e.x = t.motion.x_m();
    e.z = t.motion.z_m();
    e.y = t.y_m;
    e.theta = t.theta_rad;
    e.W = t.W;
    e.H = t.H;
    e.L = t.L;
}

/// The entity of a track missed in this frame: its predicted box, the confidence of its last
/// detection halved for every frame missed, no supporting points.
scene_schema::Entity predicted(const Track& t, const TrackerOptions& o,
                               const scene_schema::EntityDocument& frame) {
    scene_schema::Entity e;
    e.id = track_entity_id(t.id, frame);
    e.class_name = t.class_name;
    e.class_id = t.class_id;
    e.confidence = t.confidence * std::pow(0.5, t.misses + (t.seen_in_part > 0 ? 1 : 0));
    e.point_count = 0;
    e.method = "track prediction";
    report(t, o, e);
    return e;
}

/// Whether a still track missed in `frame` is seen in part there (TrackerOptions::
/// support_frames): an entity of a support class, not matched to a track of the track's class
/// (a car passing over a parked car's place is no piece of it), has its centre on the track's
/// footprint grown by the margin.
bool seen_in_part(const Track& t, const TrackerOptions& o,
                  const scene_schema::EntityDocument& frame, const std::vector<int>& track_of,
                  const std::vector<Track>& tracks) {
    if (o.support_frames <= 0 || t.seen_in_part >= o.support_frames || !is_still(t, o)) {
        return false;
    }
    for (std::size_t i = 0; i < frame.entities.size(); ++i) {
        const auto& e = frame.entities[i];
        if (!in(o.support_classes, e.class_name) ||
            (track_of[i] >= 0 &&
             tracks[static_cast<std::size_t>(track_of[i])].class_name == t.class_name)) {
            continue;
        }
        if (on_footprint(e.x, e.z, t.motion.x_m(), t.motion.z_m(), t.theta_rad, t.L, t.W,
                         o.support_margin_m)) {
            return true;
        }
    }
    return false;
}

}  // namespace

std::string track_entity_id(std::int64_t track_id, const scene_schema::EntityDocument& frame) {
    const std::string base = "track-" + std::to_string(track_id);
    std::string id = base;
    for (int k = 2; std::any_of(frame.entities.begin(), frame.entities.end(),
                                [&](const scene_schema::Entity& other) { return other.id == id; });
         ++k) {
        id = base + "-" + std::to_string(k);
    }
    return id;
}

bool is_still(const Track& t, const TrackerOptions& o) {
    return t.confirmed && t.hits >= o.coast_min_hits && velocity_known(t, o) &&
           std::hypot(t.motion.vx_mps(), t.motion.vz_mps()) <= o.still_max_speed_mps;
}

bool on_footprint(double x_m, double z_m, double cx_m, double cz_m, double theta_rad, double L_m,
                  double W_m, double margin_m) {
    const BoxAxes axes(theta_rad);
    const double dx = x_m - cx_m, dz = z_m - cz_m;
    return std::abs(axes.along(dx, dz)) <= 0.5 * L_m + margin_m &&
           std::abs(axes.across(dx, dz)) <= 0.5 * W_m + margin_m;
}

bool footprint_in_view(double x_m, double z_m, double theta_rad, double L_m, double W_m,
                       const std::optional<scene_schema::CameraIntrinsics>& camera) {
    if (!camera || !(camera->fx_px > 0.0) || camera->width_px <= 0) return true;
    constexpr double kNearestM = 0.5;  // in front of the camera, not at its centre
    const auto corners = BoxAxes(theta_rad).corners(x_m, z_m, L_m, W_m);
    return std::any_of(corners.begin(), corners.end(), [&](const Eigen::Vector2d& p) {
        if (!(p.y() > kNearestM)) return false;
        const double u = camera->fx_px * p.x() / p.y() + camera->cx_px;
        return u >= 0.0 && u <= static_cast<double>(camera->width_px);
    });
}

double Tracker::advance_clock(double timestamp_s, TrackerFrameStats& s) {
    double dt = 0.0;
    if (last_time_s_) {
        dt = timestamp_s - *last_time_s_;
        if (!(dt > 0.0) || dt > options_.max_gap_s) {
            reset();
            s.restarted = true;
            dt = 0.0;
        }
    }
    last_time_s_ = timestamp_s;
    return dt;
}

void Tracker::take_detections(const scene_schema::EntityDocument& frame, std::vector<int>& track_of,
                              std::vector<char>& hit, scene_schema::EntityDocument& out,
                              TrackerFrameStats& s) {
    for (std::size_t i = 0; i < frame.entities.size(); ++i) {
        if (track_of[i] == -2) continue;
        ++s.detections;
        const auto& e = frame.entities[i];
        if (track_of[i] >= 0) {
            Track& t = tracks_[track_of[i]];
            t.motion.update(e.x, e.z);
            t.still.update(e.x, e.z);
            if (absorb(t, e, options_)) s.turned.push_back(t.id);
            t.confidence = e.confidence;
            ++t.hits;
            t.misses = 0;
            t.seen_in_part = 0;
            hit[track_of[i]] = 1;
            ++s.matched;
        } else {
            track_of[i] = static_cast<int>(tracks_.size());
            tracks_.push_back(born(e, next_id_++, options_));
            hit.push_back(1);
            ++s.born;
        }
        Track& t = tracks_[track_of[i]];
        const bool was_confirmed = t.confirmed;
        if (!t.confirmed &&
            (t.hits >= options_.min_hits ||
             (options_.confirm_first_frames && frames_since_start_ <= options_.min_hits))) {
            t.confirmed = true;
            t.size_locked = true;
            t.sum_W = t.sum_H = t.sum_L = 0.0;
            t.size_samples = 0;
        }
        if (t.confirmed) {
            report(t, options_, out.entities[i]);
            ++s.reported;
            if (!was_confirmed && !t.tentative_entity_ids.empty()) {
                s.confirmed.push_back(
                    ConfirmedTrack{t.id, std::move(t.tentative_entity_ids), out.entities[i]});
                t.tentative_entity_ids.clear();
            }
        } else {
            t.tentative_entity_ids.push_back(e.id);
        }
    }
}

void Tracker::age_tracks(const scene_schema::EntityDocument& frame,
                         const std::vector<int>& track_of, const std::vector<char>& hit,
                         scene_schema::EntityDocument& out, TrackerFrameStats& s) {
    // Misses; tentative tracks die at their first, confirmed ones after max_misses. A
    // confirmed track of at least coast_min_hits hits missed for at most coast_frames frames
    // is reported at its prediction.
    std::vector<Track> alive;
    alive.reserve(tracks_.size());
    for (std::size_t k = 0; k < tracks_.size(); ++k) {
        Track& t = tracks_[k];
        const bool in_part = !hit[k] && seen_in_part(t, options_, frame, track_of, tracks_);
        if (in_part) {
            ++t.seen_in_part;
        } else if (!hit[k]) {
            ++t.misses;
        }
        const bool dead = t.misses > 0 && (!t.confirmed || t.misses >= options_.max_misses);
        if (dead) {
            ++s.died;
            continue;
        }
        if (!hit[k] && (in_part || t.misses <= options_.coast_frames) &&
            t.hits >= options_.coast_min_hits &&
            footprint_in_view(t.motion.x_m(), t.motion.z_m(), t.theta_rad, t.L, t.W,
                              frame.frame.camera)) {
            out.entities.push_back(predicted(t, options_, out));
            ++s.reported;
            ++s.coasted;
        }
        alive.push_back(std::move(t));
    }
    tracks_ = std::move(alive);
}

scene_schema::EntityDocument Tracker::update(const scene_schema::EntityDocument& frame,
                                             double timestamp_s, TrackerFrameStats* stats) {
    if (!std::isfinite(timestamp_s)) throw std::invalid_argument("timestamp is not finite");
    TrackerFrameStats s;
    const double dt = advance_clock(timestamp_s, s);
    ++frames_since_start_;
    if (frame.frame.pose && last_pose_) carry(*last_pose_, *frame.frame.pose);
    last_pose_ = frame.frame.pose;
    predict(dt);

    std::vector<int> track_of;
    associate(frame, track_of);
    std::vector<char> hit(tracks_.size(), 0);
    scene_schema::EntityDocument out = frame;
    out.frame.timestamp_s = timestamp_s;
    take_detections(frame, track_of, hit, out, s);
    ++frame_number_;
    record_steps();
    age_tracks(frame, track_of, hit, out, s);
    if (stats) *stats = s;
    return out;
}

void Tracker::record_steps() {
    for (Track& t : tracks_) {
        const KalmanStep step = t.motion.close_step();
        if (options_.history_frames <= 0) continue;
        History& h = histories_[t.id];
        h.steps.push_back(step);
        h.last_frame = frame_number_;
        while (h.steps.size() > static_cast<std::size_t>(options_.history_frames)) {
            h.steps.pop_front();
        }
    }
    for (auto it = histories_.begin(); it != histories_.end();) {
        it = it->second.last_frame + options_.history_frames <= frame_number_ ? histories_.erase(it)
                                                                              : std::next(it);
    }
}

std::optional<Eigen::Vector4d> Tracker::smoothed(std::int64_t id, std::int64_t frame) const {
    const auto it = histories_.find(id);
    if (it == histories_.end()) return std::nullopt;
    const History& h = it->second;
    const auto first = h.last_frame - static_cast<std::int64_t>(h.steps.size()) + 1;
    if (frame < first || frame > h.last_frame) return std::nullopt;
    return smooth_states(h.steps)[static_cast<std::size_t>(frame - first)];
}

std::vector<scene_schema::EntityDocument> track_sequence(
    const std::vector<scene_schema::EntityDocument>& frames, const std::vector<double>& times_s,
    const TrackerOptions& options) {
    if (frames.size() != times_s.size()) {
        throw std::invalid_argument("track_sequence: one timestamp per frame is needed");
    }
    Tracker tracker(options);
    std::vector<scene_schema::EntityDocument> out;
    out.reserve(frames.size());
    for (std::size_t i = 0; i < frames.size(); ++i)
        out.push_back(tracker.update(frames[i], times_s[i]));
    return out;
}

}  // namespace cloud_analysis::tracking
