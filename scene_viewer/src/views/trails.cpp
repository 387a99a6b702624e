#include "scene_viewer/views/trails.hpp"

#include <algorithm>
#include <array>
#include <cstring>
#include <optional>

#include "scene_viewer/ecs/coordinates.hpp"

namespace scene_viewer {

namespace {

/// The point (x, y, z) moved by the 4x4 matrix T.
std::array<double, 3> apply(const glm::dmat4& T, double x, double y, double z) {
    const glm::dvec4 p = T * glm::dvec4(x, y, z, 1.0);
    return {p.x, p.y, p.z};
}

}  // namespace

void TrailHistory::remember(const scene_schema::EntityDocument& frame) {
    if (length_ <= 0) return;
    const auto push = [this](std::int64_t track, const std::array<double, 3>& p, int class_id) {
        auto& trail = points_[track];
        trail.push_back({p[0], p[1], p[2], class_id});
        while (static_cast<int>(trail.size()) > length_) trail.pop_front();
    };
    std::optional<glm::dmat4> world_from_camera;
    if (frame.frame.pose) world_from_camera = kitti_pose_matrix(*frame.frame.pose);
    for (const auto& e : frame.entities) {
        if (!e.track_id) continue;
        const double y_ground = e.y + e.H / 2.0;
        push(*e.track_id,
             world_from_camera ? apply(*world_from_camera, e.x, y_ground, e.z)
                               : std::array{e.x, y_ground, e.z},
             e.class_id);
    }
    // The camera's own path: the point on the ground under it.
    if (world_from_camera) {
        push(kEgoTrack, apply(*world_from_camera, 0.0, kEgoGroundBelow_m, 0.0), kEgoClassId);
    }
}

scene_schema::EntityDocument TrailHistory::with_trails(
    const scene_schema::EntityDocument& frame) const {
    scene_schema::EntityDocument out = frame;
    std::optional<glm::dmat4> camera_from_world;
    if (frame.frame.pose) camera_from_world = glm::inverse(kitti_pose_matrix(*frame.frame.pose));
    for (const auto& [track, trail] : points_) {
        for (std::size_t k = 0; k < trail.size(); ++k) {
            const Point& p = trail[k];
            const auto c = camera_from_world ? apply(*camera_from_world, p.x, p.y_ground, p.z)
                                             : std::array{p.x, p.y_ground, p.z};
            scene_schema::Entity m;
            m.id = (track == kEgoTrack ? std::string("trail-ego-")
                                       : "trail-" + std::to_string(track) + "-") +
                   std::to_string(k);
            m.class_name = "trail";
            m.class_id = p.class_id;
            m.x = c[0];
            m.z = c[2];
            m.H = 0.04;
            m.y = c[1] - m.H / 2.0;
            m.W = 0.35;
            m.L = 0.35;
            m.method = "trail";
            out.entities.push_back(m);
        }
    }
    return out;
}

ImageRgba8 side_by_side(const std::vector<ImageRgba8>& images) {
    ImageRgba8 strip;
    for (const auto& image : images) {
        strip.width += image.width;
        strip.height = std::max(strip.height, image.height);
    }
    strip.pixels.assign(static_cast<std::size_t>(strip.width) * strip.height * 4, 0);
    for (std::size_t i = 3; i < strip.pixels.size(); i += 4) strip.pixels[i] = 255;
    int x0 = 0;
    for (const auto& image : images) {
        for (int y = 0; y < image.height; ++y) {
            std::memcpy(&strip.pixels[(static_cast<std::size_t>(y) * strip.width + x0) * 4],
                        &image.pixels[static_cast<std::size_t>(y) * image.width * 4],
                        static_cast<std::size_t>(image.width) * 4);
        }
        x0 += image.width;
    }
    return strip;
}

}  // namespace scene_viewer
