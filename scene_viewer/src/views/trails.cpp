#include "scene_viewer/views/trails.hpp"

#include <algorithm>
#include <cstring>

namespace scene_viewer {

void TrailHistory::remember(const scene_schema::EntityDocument& frame) {
    if (length_ <= 0) return;
    for (const auto& e : frame.entities) {
        if (!e.track_id) continue;
        auto& trail = points_[*e.track_id];
        trail.push_back({e.x, e.y + e.H / 2.0, e.z, e.class_id});
        while (static_cast<int>(trail.size()) > length_) trail.pop_front();
    }
}

scene_schema::EntityDocument TrailHistory::with_trails(
    const scene_schema::EntityDocument& frame) const {
    scene_schema::EntityDocument out = frame;
    for (const auto& [track, trail] : points_) {
        for (std::size_t k = 0; k < trail.size(); ++k) {
            const Point& p = trail[k];
            scene_schema::Entity m;
            m.id = "trail-" + std::to_string(track) + "-" + std::to_string(k);
            m.class_name = "trail";
            m.class_id = p.class_id;
            m.x = p.x;
            m.z = p.z;
            m.H = 0.04;
            m.y = p.y_ground - m.H / 2.0;
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
