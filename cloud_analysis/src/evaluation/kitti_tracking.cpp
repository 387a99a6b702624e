#include <cmath>
#include <sstream>
#include <stdexcept>

#include "cloud_analysis/evaluation/kitti_labels.hpp"
#include "cloud_analysis/evaluation/track_eval.hpp"

namespace cloud_analysis {

namespace {

/// Central differences of each track's positions over frame numbers, times fps.
void add_velocities(std::map<std::int64_t, std::vector<TrackedObject>>& frames, double fps) {
    std::map<std::int64_t, std::vector<std::pair<std::int64_t, TrackedObject*>>> by_track;
    for (auto& [frame, objects] : frames) {
        for (auto& o : objects) by_track[o.track_id].emplace_back(frame, &o);
    }
    for (auto& [id, seen] : by_track) {
        if (seen.size() < 2) continue;
        for (std::size_t i = 0; i < seen.size(); ++i) {
            const auto& a = seen[i == 0 ? 0 : i - 1];
            const auto& b = seen[i + 1 == seen.size() ? i : i + 1];
            const double dt = static_cast<double>(b.first - a.first) / fps;
            if (dt <= 0.0) continue;
            seen[i].second->box.velocity = scene_schema::Velocity{
                (b.second->box.x - a.second->box.x) / dt, (b.second->box.z - a.second->box.z) / dt};
        }
    }
}

}  // namespace

std::map<std::int64_t, std::vector<TrackedObject>> parse_kitti_tracking_labels(
    std::string_view text, const std::string& origin, double fps) {
    if (!(fps > 0.0 && std::isfinite(fps))) throw std::invalid_argument("fps must be > 0");
    // Split off "frame track_id" and hand the rest, line for line, to the label_2 reader.
    std::istringstream in{std::string(text)};
    std::string line, rest;
    std::vector<std::pair<std::int64_t, std::int64_t>> keys;
    int number = 0;
    while (std::getline(in, line)) {
        ++number;
        std::istringstream fields(line);
        long long frame = 0, track = 0;
        std::string first;
        if (!(fields >> first)) {
            rest += "\n";
            continue;
        }
        std::istringstream head(first);
        if (!(head >> frame) || !(fields >> track) || frame < 0) {
            throw std::runtime_error("cannot read KITTI tracking labels: line " +
                                     std::to_string(number) +
                                     ": expected a frame number and a track id (" + origin + ")");
        }
        std::string remainder;
        std::getline(fields, remainder);
        rest += remainder + "\n";
        keys.emplace_back(frame, track);
    }
    const auto labels = parse_kitti_labels(rest, origin);
    std::map<std::int64_t, std::vector<TrackedObject>> frames;
    for (std::size_t i = 0; i < labels.size(); ++i) {
        const KittiLabel& label = labels[i];
        const auto [frame, track] = keys[i];
        auto& objects = frames[frame];  // a frame with only DontCare still exists
        const bool van = label.type == "Van";
        const auto klass = class_of_kitti_type(van ? "Car" : label.type);
        if (!klass || track < 0) continue;
        auto entity = entities_from_kitti_labels({label});
        if (entity.empty()) continue;
        TrackedObject o{track, entity.front(), !van && label.occluded < 2};
        o.box.track_id = track;
        objects.push_back(o);
    }
    add_velocities(frames, fps);
    return frames;
}

}  // namespace cloud_analysis
