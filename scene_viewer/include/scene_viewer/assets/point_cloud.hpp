#pragma once

/// Small readers for the point clouds cloud-analysis writes, for the overlay (no PCL here):
/// PLY (binary little-endian or ASCII; x y z, red green blue, and a class property such as
/// scalar_class), PCD v0.7 (ascii or binary; x y z rgb label) and ASCII .xyz with a `//` header.

#include <array>
#include <cstdint>
#include <filesystem>
#include <istream>
#include <vector>

#include <glm/glm.hpp>

namespace scene_viewer {

/// Points in the KITTI camera frame (metres), with optional colours and class ids.
struct PointCloud {
    std::vector<glm::vec3> positions_kitti;
    std::vector<std::array<std::uint8_t, 3>> colours;  ///< empty or one per point
    std::vector<int> class_ids;                        ///< empty or one per point
    std::size_t size() const { return positions_kitti.size(); }
};

/// Reads by extension (.ply, .pcd, .xyz/.txt); throws std::runtime_error naming the file and
/// the problem (unsupported format, missing x/y/z, truncated data).
/// The file is checked by the bounded reader's rules (a regular file within the size limit)
/// and then parsed by the stream overload.
PointCloud read_point_cloud(const std::filesystem::path& path);

/// Parses a cloud from a stream; `path` picks the format by its extension and is named in errors.
PointCloud read_point_cloud(std::istream& in, const std::filesystem::path& path);

}  // namespace scene_viewer
