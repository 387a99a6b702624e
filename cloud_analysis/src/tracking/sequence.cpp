#include "cloud_analysis/tracking/sequence.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <set>
#include <stdexcept>

namespace cloud_analysis::tracking {

namespace fs = std::filesystem;

void SequenceTrackOptions::validate() const {
    if (!(fps > 0.0 && fps <= 1000.0)) throw std::invalid_argument("fps must be in (0, 1000]");
    tracker.validate();
}

scene_schema::SequenceIndex read_frames(const fs::path& input) {
    std::error_code ec;
    if (!fs::is_directory(input, ec)) return scene_schema::read_sequence_file(input);
    if (fs::exists(input / "sequence.json")) {
        return scene_schema::read_sequence_file(input / "sequence.json");
    }
    std::vector<std::string> names;
    for (const auto& entry : fs::directory_iterator(input, ec)) {
        if (entry.is_regular_file() && entry.path().extension() == ".json") {
            names.push_back(entry.path().filename().string());
        }
    }
    if (ec) throw scene_schema::FileError(input.string() + ": cannot list: " + ec.message());
    if (names.empty()) throw scene_schema::FileError(input.string() + ": no entity files (*.json)");
    std::sort(names.begin(), names.end());
    scene_schema::SequenceIndex index;
    index.id = fs::absolute(input).lexically_normal().filename().string();
    if (index.id.empty()) index.id = "drive";
    for (std::size_t i = 0; i < names.size(); ++i) {
        index.frames.push_back({static_cast<std::int64_t>(i), names[i], std::nullopt, {}});
    }
    return index;
}

SequenceTrackReport track_files(const scene_schema::SequenceIndex& index,
                                const fs::path& index_path, const fs::path& out_dir,
                                const SequenceTrackOptions& options,
                                const std::function<void(const std::string&)>& warn) {
    options.validate();
    const double fps = index.fps.value_or(options.fps);
    Tracker tracker(options.tracker);
    SequenceTrackReport report;
    report.frames = index.frames.size();
    scene_schema::SequenceIndex written;
    written.id = index.id;
    written.fps = fps;
    std::set<std::int64_t> ids;
    std::optional<double> last_time;
    for (const auto& f : index.frames) {
        scene_schema::EntityDocument doc;
        try {
            doc = scene_schema::read_file(scene_schema::frame_file(index_path, f));
        } catch (const std::exception& e) {
            warn(std::string(e.what()) + " (frame " + std::to_string(f.index) + " skipped)");
            ++report.skipped;
            continue;
        }
        const double t = doc.frame.timestamp_s.value_or(f.timestamp_s.value_or(f.index / fps));
        if (last_time && t <= *last_time) {
            warn(f.file + ": timestamp " + std::to_string(t) + " s is not after the previous " +
                 std::to_string(*last_time) + " s (the tracker restarts)");
        }
        TrackerFrameStats stats;
        const auto start = std::chrono::steady_clock::now();
        const auto tracked = tracker.update(doc, t, &stats);
        report.track_ms +=
            std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start)
                .count();
        if (stats.restarted) ++report.restarts;
        for (const auto& e : tracked.entities) {
            if (e.track_id) ids.insert(*e.track_id);
        }
        scene_schema::write_file(tracked, out_dir / f.file);
        // The index may only say time goes forward: a restart after time went back keeps the
        // previous timestamp's order by leaving this frame's out.
        scene_schema::SequenceFrame entry{f.index, f.file, t, {}};
        if (last_time && t < *last_time) entry.timestamp_s.reset();
        if (entry.timestamp_s) last_time = t;
        written.frames.push_back(entry);
        scene_schema::write_sequence_file(written, out_dir / "sequence.json");
        ++report.tracked;
    }
    if (written.frames.empty())
        scene_schema::write_sequence_file(written, out_dir / "sequence.json");
    report.tracks = ids.size();
    return report;
}

}  // namespace cloud_analysis::tracking
