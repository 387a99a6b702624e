#pragma once

/// What a resumed batch trusts: a frame counts as done when every output it asks for exists,
/// is complete and is valid (the entity file passes the schema and names the frame; each cloud
/// file holds exactly the points its header declares, and the clouds agree; the disparity PNG
/// ends with its IEND chunk). The batch writes the entity file last, so a frame whose writer
/// was killed has no valid entity file and is redone. See docs/cluster.md.

#include <cstddef>
#include <filesystem>
#include <string>
#include <vector>

namespace cloud_analysis {

/// The files a batch writes for each frame.
struct FrameOutputs {
    std::vector<std::string> cloud_formats;  ///< cloud file extensions: any of xyz pcd ply
    bool disparity_kitti = false;            ///< <frame>_disparity.png (KITTI 16-bit) too
};

/// The output paths of a frame, in the order the batch writes them: disparity, clouds, and the
/// entity file `<out_dir>/<frame>.json` last.
std::vector<std::filesystem::path> frame_output_paths(const std::filesystem::path& out_dir,
                                                      const std::string& frame,
                                                      const FrameOutputs& outputs);

/// Why the frame's outputs are not all there, complete and valid ("<file>: <why>"), or ""
/// when they are.
std::string frame_outputs_problem(const std::filesystem::path& out_dir, const std::string& frame,
                                  const FrameOutputs& outputs);

/// Points in a .xyz, .pcd or .ply file written by cloud-analysis, after checking that the
/// file's size is what its header declares (a truncated or padded file fails); throws
/// std::runtime_error saying what is wrong.
std::size_t cloud_file_points(const std::filesystem::path& path);

/// Removes the temporary files a killed writer left beside these frames' outputs
/// (`.<name>.tmp-XXXXXX`, see stereoscene::support::write_file_atomic); only those of the given
/// frames, so shards sharing a folder do not touch each other's. Returns how many were removed.
std::size_t remove_stale_temporaries(const std::filesystem::path& out_dir,
                                     const std::vector<std::string>& frames,
                                     const FrameOutputs& outputs);

}  // namespace cloud_analysis
