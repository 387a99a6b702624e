#include "scene_viewer/sensors/drive.hpp"

#include <cmath>
#include <cstdio>
#include <stdexcept>

namespace scene_viewer {

namespace {

/// Cityscapes labelIds with instances (person 24 .. bicycle 33), as the instance image's.
bool is_thing(int class_id) { return class_id >= 24 && class_id <= 33; }

}  // namespace

void DriveOptions::validate() const {
    if (frames < 1 || frames > 100000) {
        throw std::invalid_argument("--frames must be between 1 and 100000");
    }
    if (!(fps > 0.0 && fps <= 1000.0)) throw std::invalid_argument("--fps must be in (0, 1000]");
}

std::string drive_frame_name(int index) {
    char name[16];
    std::snprintf(name, sizeof name, "%010d", index);
    return name;
}

scene_schema::EntityDocument scene_at(const scene_schema::EntityDocument& scene, double t_s,
                                      const std::string& frame_name) {
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
