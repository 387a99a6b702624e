#pragma once

/// A drive's entity files tracked in order: read frame by frame, tracked (tracker.hpp), each
/// written with its track ids as soon as it is done, with the sequence index rewritten after
/// every frame, so a run stopped half-way leaves complete, valid frames and an index of them.

#include <deque>
#include <filesystem>
#include <functional>
#include <optional>
#include <set>
#include <string>

#include "cloud_analysis/tracking/hindsight.hpp"
#include "cloud_analysis/tracking/tracker.hpp"
#include "scene_schema/sequence.hpp"

namespace cloud_analysis::tracking {

/// Settings of track_files.
struct SequenceTrackOptions {
    double fps = 10.0;       ///< frame rate when neither the index nor a file has timestamps, Hz
    TrackerOptions tracker;  ///< association, birth, death, smoothing
    /// track_files holds this many frames before writing them: a track whose motion shows,
    /// within that many frames, that its box was reported facing backwards is turned round in
    /// the held frames too (no heading flip in the output), and a track confirmed after
    /// min_hits detections is reported in the held frames of its earlier ones as well (an
    /// object is followed from its first detection), and the still objects of the newest frame
    /// are placed in them (`hindsight`). 0 writes each frame at once.
    int lag_frames = 30;
    /// Whether each held frame is written with its tracks' smoothed positions and velocities:
    /// the filter's states given the frames after it, up to the newest held (fixed-lag
    /// Rauch-Tung-Striebel smoothing; a car first seen far is placed by what its nearer
    /// views showed). Off, each frame keeps the filter's state as it was then.
    bool smooth = true;
    /// Whether each held frame also reports the tracks still in the newest frame where its
    /// camera sees their place (hindsight.hpp: a parked car first seen far, merged with its
    /// neighbour or lost, placed where its nearer views put it).
    bool hindsight = true;
    /// Throws std::invalid_argument naming the bad field.
    void validate() const;
};

/// The frames of `input`: a sequence index file, or a folder whose sequence.json is read when
/// present and whose *.json entity files are otherwise taken in name order (index = position).
/// Throws scene_schema::FileError naming the file or folder.
scene_schema::SequenceIndex read_frames(const std::filesystem::path& input);

/// What track_files did.
struct SequenceTrackReport {
    std::size_t frames = 0;    ///< frames in the input
    std::size_t tracked = 0;   ///< frames written
    std::size_t skipped = 0;   ///< unreadable frames (warned, left out)
    std::size_t restarts = 0;  ///< tracker restarts (gaps, time going back)
    std::size_t tracks = 0;    ///< distinct track ids written
    double track_ms = 0.0;     ///< time spent in the tracker, ms
};

/// Frames tracked as they come (a batch's frames in order, or track_files'): each tracked, then
/// written by the caller, then added to the index, which is rewritten after every frame.
class SequenceTracker {
  public:
    /// `id` and `fps` go to the index; `warn` gets "<file>: <reason>" warnings.
    SequenceTracker(std::string id, double fps, const SequenceTrackOptions& options,
                    std::function<void(const std::string&)> warn);

    /// Tracks frame number `index` (to be written as `file`, relative to the index) at
    /// doc.frame.timestamp, else `time_s`, else index / fps; returns the tracked document. Time
    /// going back is warned about and restarts the tracker.
    scene_schema::EntityDocument track(const scene_schema::EntityDocument& doc, std::int64_t index,
                                       const std::string& file, std::optional<double> time_s);

    /// Adds the oldest frame tracked and not yet committed to the index and writes it to
    /// `index_path` (atomically; durably with kDurable). Without such a frame, writes the
    /// index as it is.
    void commit(const std::filesystem::path& index_path,
                stereoscene::support::FileSync sync = stereoscene::support::FileSync::kAtomicOnly);

    /// Leaves the oldest frame not yet committed out of the index (its file could not be
    /// written).
    void discard() {
        if (!pending_.empty()) pending_.pop_front();
    }
    /// The tracker's number of the frame the last track() took (Tracker::frame_number).
    std::int64_t frame_number() const { return tracker_.frame_number(); }
    /// A track's smoothed state in a frame numbered by frame_number() (Tracker::smoothed).
    std::optional<Eigen::Vector4d> smoothed(std::int64_t id, std::int64_t frame) const {
        return tracker_.smoothed(id, frame);
    }
    /// What the newest frame tracked knows of its still objects (hindsight_of).
    Hindsight hindsight() const {
        return hindsight_of(tracker_, tracker_.options(), tracker_.last_pose());
    }
    /// The tracker's settings.
    const TrackerOptions& tracker_options() const { return tracker_.options(); }
    /// The frame_number() of the last restart's frame (0 before any).
    std::int64_t restart_frame() const { return restart_frame_; }
    /// Tracks the last track() turned round by pi (see TrackerFrameStats::turned).
    const std::vector<std::int64_t>& turned() const { return turned_; }
    /// Tracks the last track() confirmed after earlier hits (see TrackerFrameStats::confirmed).
    const std::vector<ConfirmedTrack>& confirmed() const { return confirmed_; }

    /// Counts a frame that could not be read or analysed (the tracker sees a gap).
    void skip() { ++report_.skipped; }

    /// What was tracked so far (frames = tracked + skipped).
    SequenceTrackReport report() const;

  private:
    Tracker tracker_;
    std::int64_t restart_frame_ = 0;  ///< see restart_frame()
    std::function<void(const std::string&)> warn_;
    double fps_;
    scene_schema::SequenceIndex written_;
    std::deque<scene_schema::SequenceFrame> pending_;  ///< tracked, not yet committed
    std::optional<double> last_time_;  ///< of the last frame tracked with a usable timestamp
    std::vector<std::int64_t> turned_;
    std::vector<ConfirmedTrack> confirmed_;
    std::set<std::int64_t> ids_;
    SequenceTrackReport report_;
};

/// Tracks every frame of `index` (files relative to `index_path`'s folder) and writes
/// <out_dir>/<file> plus <out_dir>/sequence.json (timestamps filled in). A frame that cannot
/// be read is reported to `warn` ("<file>: <reason>") and skipped; so is a time going back or
/// a gap longer than max_gap_s (the tracker restarts). Throws when out_dir cannot be written.
SequenceTrackReport track_files(const scene_schema::SequenceIndex& index,
                                const std::filesystem::path& index_path,
                                const std::filesystem::path& out_dir,
                                const SequenceTrackOptions& options,
                                const std::function<void(const std::string&)>& warn);

}  // namespace cloud_analysis::tracking
