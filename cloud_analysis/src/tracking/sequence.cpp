#include "cloud_analysis/tracking/sequence.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <deque>
#include <set>
#include <stdexcept>
#include "stereoscene/support/angles.hpp"

namespace cloud_analysis::tracking {

namespace fs = std::filesystem;

namespace {

using stereoscene::support::kPi;
using stereoscene::support::wrap_angle;

/// A frame tracked but not yet written.
struct HeldFrame {
    scene_schema::EntityDocument doc;
    std::string file;
    std::int64_t number = 0;  ///< the tracker's frame number
};
/// Frames tracked but not yet written, oldest first.
using HeldFrames = std::deque<HeldFrame>;

/// Moves the tracked entities of `frame` to their tracks' smoothed positions and velocities.
void smooth_frame(HeldFrame& frame, const SequenceTracker& sequence) {
    for (scene_schema::Entity& e : frame.doc.entities) {
        if (!e.track_id) continue;
        const auto s = sequence.smoothed(*e.track_id, frame.number);
        if (!s) continue;
        e.x = (*s)(0);
        e.z = (*s)(1);
        if (e.velocity) e.velocity = scene_schema::Velocity{(*s)(2), (*s)(3)};
    }
}

/// The tracker's settings, keeping the filter steps the held frames' smoothing needs.
TrackerOptions with_history(const SequenceTrackOptions& options) {
    options.validate();  // a bad lag is named as such, not as the history it sizes
    TrackerOptions o = options.tracker;
    o.history_frames = options.smooth ? options.lag_frames + 1 : 0;
    return o;
}

/// A track confirmed in the newest held frame is reported in the held frames before it, on the
/// entities it was made of there: its id, velocity, heading and held size (each keeps its own
/// measured centre). An entity another track already reports is left alone.
void report_earlier(HeldFrames& held, const std::vector<ConfirmedTrack>& confirmed) {
    for (const ConfirmedTrack& c : confirmed) {
        const std::size_t n = c.earlier_entity_ids.size();
        for (std::size_t k = 1; k <= n && k < held.size(); ++k) {
            const std::string& id = c.earlier_entity_ids[n - k];
            for (scene_schema::Entity& e : held[held.size() - 1 - k].doc.entities) {
                if (e.id != id || e.track_id) continue;
                e.track_id = c.id;
                e.velocity = c.reported.velocity;
                e.theta = c.reported.theta;
                e.W = c.reported.W;
                e.H = c.reported.H;
                e.L = c.reported.L;
            }
        }
    }
}

}  // namespace

void SequenceTrackOptions::validate() const {
    if (!(fps > 0.0 && fps <= 1000.0)) throw std::invalid_argument("fps must be in (0, 1000]");
    if (lag_frames < 0 || lag_frames > 1000)
        throw std::invalid_argument("lag_frames must be in 0..1000");
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

SequenceTracker::SequenceTracker(std::string id, double fps, const SequenceTrackOptions& options,
                                 std::function<void(const std::string&)> warn)
    : tracker_(with_history(options)), warn_(std::move(warn)), fps_(fps) {
    if (!(fps > 0.0 && fps <= 1000.0)) throw std::invalid_argument("fps must be in (0, 1000]");
    written_.id = std::move(id);
    written_.fps = fps;
}

scene_schema::EntityDocument SequenceTracker::track(const scene_schema::EntityDocument& doc,
                                                    std::int64_t index, const std::string& file,
                                                    std::optional<double> time_s) {
    const double t = doc.frame.timestamp_s.value_or(time_s.value_or(index / fps_));
    if (last_time_ && t <= *last_time_) {
        warn_(file + ": timestamp " + std::to_string(t) + " s is not after the previous " +
              std::to_string(*last_time_) + " s (the tracker restarts)");
    }
    TrackerFrameStats stats;
    const auto start = std::chrono::steady_clock::now();
    scene_schema::EntityDocument tracked = tracker_.update(doc, t, &stats);
    report_.track_ms +=
        std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
    if (stats.restarted) {
        ++report_.restarts;
        restart_frame_ = tracker_.frame_number();
    }
    turned_ = std::move(stats.turned);
    confirmed_ = std::move(stats.confirmed);
    for (const auto& e : tracked.entities) {
        if (e.track_id) ids_.insert(*e.track_id);
    }
    // The index may only say time goes forward: a restart after time went back keeps the
    // previous timestamp's order by leaving this frame's out.
    pending_.push_back(scene_schema::SequenceFrame{index, file, t, {}});
    if (last_time_ && t < *last_time_) {
        pending_.back().timestamp_s.reset();
    } else {
        last_time_ = t;
    }
    return tracked;
}

void SequenceTracker::commit(const fs::path& index_path, stereoscene::support::FileSync sync) {
    if (!pending_.empty()) {
        written_.frames.push_back(std::move(pending_.front()));
        pending_.pop_front();
        ++report_.tracked;
    }
    scene_schema::write_sequence_file(written_, index_path, sync);
}

SequenceTrackReport SequenceTracker::report() const {
    SequenceTrackReport r = report_;
    r.frames = r.tracked + r.skipped;
    r.tracks = ids_.size();
    return r;
}

SequenceTrackReport track_files(const scene_schema::SequenceIndex& index,
                                const fs::path& index_path, const fs::path& out_dir,
                                const SequenceTrackOptions& options,
                                const std::function<void(const std::string&)>& warn) {
    options.validate();
    SequenceTracker sequence(index.id, index.fps.value_or(options.fps), options, warn);
    HeldFrames held;
    // What the newest frame knows of its still objects, taken once per frame tracked.
    Hindsight known;
    const auto write_oldest = [&] {
        // Frames before the newest, back to the last restart of the tracker (whose tracks say
        // nothing of the frames before it).
        const std::int64_t number = held.front().number;
        if (options.hindsight && number >= sequence.restart_frame() &&
            number < sequence.frame_number()) {
            place_still_objects(held.front().doc, known, sequence.tracker_options());
        }
        if (options.smooth) smooth_frame(held.front(), sequence);
        scene_schema::write_file(held.front().doc, out_dir / held.front().file);
        held.pop_front();
        sequence.commit(out_dir / "sequence.json");
    };
    for (const auto& f : index.frames) {
        scene_schema::EntityDocument doc;
        try {
            doc = scene_schema::read_file(scene_schema::frame_file(index_path, f));
        } catch (const std::exception& e) {
            warn(std::string(e.what()) + " (frame " + std::to_string(f.index) + " skipped)");
            sequence.skip();
            continue;
        }
        held.push_back(HeldFrame{sequence.track(doc, f.index, f.file, f.timestamp_s), f.file,
                                 sequence.frame_number()});
        report_earlier(held, sequence.confirmed());
        if (options.hindsight) known = sequence.hindsight();
        // A track the motion turned round faced backwards in the frames still held as well.
        for (const std::int64_t id : sequence.turned()) {
            for (std::size_t k = 0; k + 1 < held.size(); ++k) {
                for (auto& e : held[k].doc.entities) {
                    if (e.track_id == id) e.theta = wrap_angle(e.theta + kPi);
                }
            }
        }
        while (held.size() > static_cast<std::size_t>(options.lag_frames)) write_oldest();
    }
    while (!held.empty()) write_oldest();
    sequence.commit(out_dir / "sequence.json", stereoscene::support::FileSync::kDurable);
    return sequence.report();
}

}  // namespace cloud_analysis::tracking
