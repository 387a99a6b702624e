#pragma once

/// A drive's entity files tracked in order: read frame by frame, tracked (tracker.hpp), each
/// written with its track ids as soon as it is done, with the sequence index rewritten after
/// every frame, so a run stopped half-way leaves complete, valid frames and an index of them.

#include <filesystem>
#include <functional>
#include <string>

#include "cloud_analysis/tracking/tracker.hpp"
#include "scene_schema/sequence.hpp"

namespace cloud_analysis::tracking {

/// Settings of track_files.
struct SequenceTrackOptions {
    double fps = 10.0;       ///< frame rate when neither the index nor a file has timestamps, Hz
    TrackerOptions tracker;  ///< association, birth, death, smoothing
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
