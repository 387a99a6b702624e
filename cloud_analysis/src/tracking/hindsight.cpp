#include "cloud_analysis/tracking/hindsight.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

#include <Eigen/LU>

namespace cloud_analysis::tracking {

namespace {

/// `o` carried into the camera `m` leads to.
StillObject carried(StillObject o, const GroundMotion& m) {
    const Eigen::Vector2d p = m.R * Eigen::Vector2d(o.x_m, o.z_m) + m.t;
    o.x_m = p.x();
    o.z_m = p.y();
    o.y_m += m.dy_m;
    o.theta_rad += m.yaw_rad;
    return o;
}

/// Writes `o` on `e`: its track, place, size, heading and (still) velocity.
void report_on(const StillObject& o, scene_schema::Entity& e) {
    e.track_id = o.id;
    e.x = o.x_m;
    e.y = o.y_m;
    e.z = o.z_m;
    e.theta = o.theta_rad;
    e.W = o.W;
    e.H = o.H;
    e.L = o.L;
    e.velocity = scene_schema::Velocity{0.0, 0.0};
}

/// A new entity for `o`, its id unused in `frame`.
scene_schema::Entity added(const StillObject& o, const scene_schema::EntityDocument& frame) {
    scene_schema::Entity e;
    e.id = track_entity_id(o.id, frame);
    e.class_name = o.class_name;
    e.class_id = o.class_id;
    e.confidence = 0.5 * o.confidence;
    e.point_count = 0;
    e.method = "track hindsight";
    report_on(o, e);
    return e;
}

/// Whether two boxes share ground: the centre of one on the other's footprint grown by `margin`.
bool overlap(const StillObject& o, const scene_schema::Entity& e, double margin) {
    return on_footprint(e.x, e.z, o.x_m, o.z_m, o.theta_rad, o.L, o.W, margin) ||
           on_footprint(o.x_m, o.z_m, e.x, e.z, e.theta, e.L, e.W, margin);
}

/// The index of the entity of `o`'s class nearest to it among those on it that no still object
/// and no moving track owns; entities.size() when none.
std::size_t piece_of(const StillObject& o, const std::vector<scene_schema::Entity>& entities,
                     const Hindsight& known, const std::set<std::int64_t>& still_ids,
                     double margin) {
    std::size_t nearest = entities.size();
    double nearest_m = std::numeric_limits<double>::infinity();
    for (std::size_t i = 0; i < entities.size(); ++i) {
        const auto& e = entities[i];
        if (e.class_name != o.class_name ||
            (e.track_id && (still_ids.count(*e.track_id) || known.moving.count(*e.track_id)))) {
            continue;
        }
        const double d = std::hypot(e.x - o.x_m, e.z - o.z_m);
        if (d < nearest_m && overlap(o, e, margin)) {
            nearest = i;
            nearest_m = d;
        }
    }
    return nearest;
}

}  // namespace

Hindsight hindsight_of(const Tracker& tracker, const TrackerOptions& options,
                       const std::optional<std::array<double, 12>>& pose) {
    Hindsight h;
    h.pose = pose;
    for (const Track& t : tracker.tracks()) {
        if (!t.confirmed) continue;
        // Still: hit often enough to be no stray, its hits those of one still point, and the
        // fit's velocity known to the speed that counts as still (a far parked car's own filter
        // knows its velocity only to a few m/s, yet its positions agree; a car driving slowly
        // for half a second near by is not yet told from a still one).
        if (t.hits < options.coast_min_hits || !t.still.consistent() ||
            t.still.velocity_sigma_mps() > options.still_max_speed_mps) {
            h.moving.insert(t.id);
            continue;
        }
        const Eigen::Vector2d p = t.still.position_m();
        h.still.push_back(StillObject{t.id, t.class_name, t.class_id, t.confidence, p.x(), t.y_m,
                                      p.y(), t.theta_rad, t.W, t.H, t.L});
    }
    std::sort(h.still.begin(), h.still.end(),
              [](const StillObject& a, const StillObject& b) { return a.id < b.id; });
    return h;
}

int place_still_objects(scene_schema::EntityDocument& frame, const Hindsight& known,
                        const TrackerOptions& options) {
    const auto& pose = frame.frame.pose;
    if (known.still.empty() || pose.has_value() != known.pose.has_value()) return 0;
    const GroundMotion m = pose ? ground_motion(*known.pose, *pose) : GroundMotion{};
    const double margin = options.support_margin_m;
    std::set<std::int64_t> reported, still_ids;
    for (const auto& e : frame.entities) {
        if (e.track_id) reported.insert(*e.track_id);
    }
    for (const auto& o : known.still) still_ids.insert(o.id);
    std::vector<StillObject> here;  // the still objects this frame reports, in its camera
    int placed = 0;
    for (const StillObject& known_object : known.still) {
        const StillObject o = carried(known_object, m);
        if (reported.count(o.id) != 0) {
            here.push_back(o);
            continue;
        }
        if (!footprint_in_view(o.x_m, o.z_m, o.theta_rad, o.L, o.W, frame.frame.camera)) continue;
        const std::size_t piece = piece_of(o, frame.entities, known, still_ids, margin);
        if (piece < frame.entities.size()) {
            report_on(o, frame.entities[piece]);
        } else {
            frame.entities.push_back(added(o, frame));
        }
        here.push_back(o);
        ++placed;
    }
    // Two solid things do not share ground: a box of another track on a still object is a
    // piece of it (a car split where it is not, or a row's box sliding along with the camera),
    // no object of its own.
    for (auto& e : frame.entities) {
        if (!e.track_id || still_ids.count(*e.track_id)) continue;
        if (std::any_of(here.begin(), here.end(), [&](const StillObject& o) {
                return o.class_name == e.class_name && overlap(o, e, margin);
            })) {
            e.track_id.reset();
            e.velocity.reset();
        }
    }
    return placed;
}

}  // namespace cloud_analysis::tracking
