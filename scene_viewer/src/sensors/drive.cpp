#include "scene_viewer/sensors/drive.hpp"

#include <cmath>
#include <cstdio>
#include <stdexcept>

#include "stereoscene/support/angles.hpp"

namespace scene_viewer {

using stereoscene::support::radians;
using stereoscene::support::wrap_angle;

namespace {

/// Cityscapes labelIds with instances (person 24 .. bicycle 33), as the instance image's.
bool is_thing(int class_id) { return class_id >= 24 && class_id <= 33; }

}  // namespace

std::array<double, 12> EgoMotion::pose_at(double t_s) const {
    const double yaw_rate = radians(yaw_rate_dps);
    const double psi = yaw_rate * t_s;
    // Heading (sin psi, 0, cos psi); the path integrates speed along it.
    double x = 0.0, z = speed_mps * t_s;
    if (std::abs(yaw_rate) > 1e-12) {
        x = speed_mps / yaw_rate * (1.0 - std::cos(psi));
        z = speed_mps / yaw_rate * std::sin(psi);
    }
    const double c = std::cos(psi), s = std::sin(psi);
    return {c, 0.0, s, x, 0.0, 1.0, 0.0, 0.0, -s, 0.0, c, z};
}

void DriveOptions::validate() const {
    if (frames < 1 || frames > 100000) {
        throw std::invalid_argument("--frames must be between 1 and 100000");
    }
    if (!(fps > 0.0 && fps <= 1000.0)) throw std::invalid_argument("--fps must be in (0, 1000]");
    if (!(std::abs(ego.speed_mps) <= 100.0)) {
        throw std::invalid_argument("--ego-speed must be within +-100 m/s");
    }
    if (!(std::abs(ego.yaw_rate_dps) <= 90.0)) {
        throw std::invalid_argument("--ego-yaw-rate must be within +-90 deg/s");
    }
}

std::string drive_frame_name(int index) {
    char name[16];
    std::snprintf(name, sizeof name, "%010d", index);
    return name;
}

scene_schema::EntityDocument scene_at(const scene_schema::EntityDocument& scene, double t_s,
                                      const std::string& frame_name, const EgoMotion& ego) {
    scene_schema::EntityDocument doc = scene;
    doc.frame.id = frame_name;
    doc.frame.timestamp_s = t_s;
    for (std::size_t i = 0; i < doc.entities.size(); ++i) {
        auto& e = doc.entities[i];
        if (e.velocity) {
            e.x += e.velocity->vx_mps * t_s;
            e.z += e.velocity->vz_mps * t_s;
        }
        if (is_thing(e.class_id) && !e.track_id) e.track_id = static_cast<std::int64_t>(i);
        if (is_thing(e.class_id) && !e.velocity) e.velocity = scene_schema::Velocity{};
    }
    if (!ego.moving()) return doc;
    const auto pose = ego.pose_at(t_s);
    doc.frame.pose = pose;
    // X_camera = R^T (X_world - t) with R a turn by psi about +y: on the ground plane
    // (x, z) -> (c x - s z, s x + c z); headings turn by -psi.
    const double c = pose[0], s = pose[2], psi = std::atan2(s, c);
    for (auto& e : doc.entities) {
        const double dx = e.x - pose[3], dz = e.z - pose[11];
        e.x = c * dx - s * dz;
        e.z = s * dx + c * dz;
        e.theta = wrap_angle(e.theta - psi);
        if (e.velocity) {
            const double vx = e.velocity->vx_mps, vz = e.velocity->vz_mps;
            e.velocity->vx_mps = c * vx - s * vz;
            e.velocity->vz_mps = s * vx + c * vz;
        }
    }
    return doc;
}

scene_schema::SequenceIndex drive_index(const std::string& id, const DriveOptions& options) {
    scene_schema::SequenceIndex index;
    index.id = id;
    index.fps = options.fps;
    for (int i = 0; i < options.frames; ++i) {
        scene_schema::SequenceFrame f;
        f.index = i;
        f.file = drive_frame_name(i) + ".json";
        f.timestamp_s = i / options.fps;
        index.frames.push_back(f);
    }
    return index;
}

}  // namespace scene_viewer
