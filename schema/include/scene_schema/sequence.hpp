#pragma once

/// The sequence index (schema 1.1): the ordered frames of a drive, each an entity file, with
/// their capture times. Specified in schema/sequence.schema.json and docs/format.md.

#include <array>
#include <cstdint>
#include <filesystem>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include <nlohmann/json.hpp>

#include "scene_schema/entities.hpp"

namespace scene_schema {

/// One frame of a sequence.
struct SequenceFrame {
    std::int64_t index = 0;             ///< frame number in the drive, strictly increasing
    std::string file;                   ///< entity file, relative to the index's folder
    std::optional<double> timestamp_s;  ///< capture time in seconds, non-decreasing
    nlohmann::json extra = nlohmann::json::object();  ///< unknown members, kept verbatim
};

/// A drive: its frames in capture order.
struct SequenceIndex {
    std::string schema_version = kSchemaVersion;
    std::string id;                                   ///< drive id, e.g. 2011_09_26_drive_0005
    std::optional<double> fps;                        ///< nominal frame rate in Hz, > 0
    std::vector<SequenceFrame> frames;                ///< in capture order, may be empty
    nlohmann::json extra = nlohmann::json::object();  ///< unknown members, kept verbatim
};

/// Every rule the index breaks, in document order (empty when valid); besides the schema's,
/// frame indices must increase strictly, timestamps must not decrease and files must be
/// relative paths without "..".
std::vector<ValidationIssue> validate_sequence(const nlohmann::json& document);

/// Validates and converts; throws SchemaError with the first issue.
SequenceIndex sequence_from_json(const nlohmann::json& document);

/// Converts back; unknown members in `extra` are written back verbatim.
nlohmann::json to_json(const SequenceIndex& index);

/// Reads and validates an index file; throws FileError "<path>: <pointer>: <rule>".
SequenceIndex read_sequence_file(const std::filesystem::path& path);

/// Validates, then writes atomically (canonical text: sorted keys, 2-space indent); kAtomicOnly
/// skips the fsync (for an index rewritten after every frame).
void write_sequence_file(
    const SequenceIndex& index, const std::filesystem::path& path,
    stereoscene::support::FileSync sync = stereoscene::support::FileSync::kDurable);

/// The entity file of `frame`, resolved against the index file's folder.
std::filesystem::path frame_file(const std::filesystem::path& index_path,
                                 const SequenceFrame& frame);

/// True when the JSON document is a sequence index (it has "frames" and no "entities").
bool is_sequence_index(const nlohmann::json& document);

/// A drive's poses (frame.pose, row-major 3x4 [R | t]) as KITTI odometry text: one pose a line,
/// 12 numbers "%.9e" apart by spaces (a zero is written 0, never -0).
std::string format_kitti_poses(const std::vector<std::array<double, 12>>& poses);

}  // namespace scene_schema
