#pragma once

/// The frames of a drive given as files rather than as a KITTI-layout root and frame ids: a
/// KITTI raw drive folder (image_02/data, image_03/data, image_02/timestamps.txt) or a list of
/// left/right(/semantic) paths, one frame a line. Pure path logic plus folder listing; the
/// images are read by the batch's loader.

#include <filesystem>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "cloud_analysis/pipeline/pipeline.hpp"

namespace cloud_analysis {

/// One frame of a drive: its id (the left image's stem), input files and capture time.
struct DriveFrame {
    std::string id;                     ///< output file stem, e.g. "0000000042"
    InputPaths paths;                   ///< left, right, semantic (may be empty), calibration
    std::optional<double> timestamp_s;  ///< capture time, seconds (Unix time for KITTI raw)
};

/// Seconds since 1970-01-01 UTC of a KITTI raw timestamp ("2011-09-26 13:02:25.964389445");
/// nothing when the text is not one.
std::optional<double> parse_kitti_timestamp(std::string_view text);

/// The frames of a KITTI raw drive folder, in name order: image_02/data/*.png with
/// image_03/data/<same name>; the semantic image <semantic_dir>/<same name> when `semantic_dir`
/// is given (it must exist for every frame), likewise the instance image in `instance_dir`;
/// calibration `calibration`, else
/// calib_cam_to_cam.txt in the drive folder or its parent (KITTI raw keeps it in the date
/// folder); times from image_02/timestamps.txt (line i for frame i) when present. Throws
/// std::runtime_error "<what>: <detail> (<path>)" for a missing folder, right image, semantic
/// image or calibration, or a timestamps file whose line count or order is wrong.
std::vector<DriveFrame> kitti_raw_drive(const std::filesystem::path& drive,
                                        const std::filesystem::path& calibration,
                                        const std::filesystem::path& semantic_dir,
                                        const std::filesystem::path& instance_dir = {});

/// The frames of a list: each line "LEFT RIGHT [SEMANTIC [INSTANCE]]" (paths relative to `base`,
/// whitespace-separated, '#' starts a comment), all with `calibration`. Frame ids are the left
/// stems and must be unique. Throws std::runtime_error naming `where` and the line.
std::vector<DriveFrame> pair_list(std::string_view text, const std::filesystem::path& base,
                                  const std::filesystem::path& calibration,
                                  const std::string& where);

}  // namespace cloud_analysis
