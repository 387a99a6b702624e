#pragma once

/// scene-render html: writes the browser viewer folder of one or more entity files.

#include <string>
#include <vector>

#include <CLI/CLI.hpp>

#include "common.hpp"

namespace scene_render::html_command {

/// Flags of `scene-render html`.
struct Options {
    std::vector<std::string> inputs;  ///< entity files (the first is the scene, more are
                                      ///< compared), or one drive (sequence index or folder)
    std::vector<std::string> labels;  ///< one label per input (default: file stems)
    std::string out_dir;              ///< output folder, created as needed
    std::string cloud;                ///< point cloud (.ply, .pcd, .xyz), or ""
    std::string background;           ///< left image shown behind the camera view, or ""
    std::string classes;              ///< class table, "" = the project's
    bool boxes = false;               ///< every entity as a box (no glTF models)
    bool no_ego = false;              ///< no ego car
    std::string title;                ///< page title, "" = the first file's stem
    float point_size_px = 2.0f;       ///< cloud point size, pixels
    int moving_points = 30000;        ///< cloud points drawn while the view moves, 0 = all
    std::string backgrounds;          ///< a drive's left images (folder, <frame>.png), or ""
    int trail = 20;                   ///< a drive's track trails, frames, 0 = none
    double fps = 0.0;                 ///< a drive's frame rate, 0 = the index's (else 10)
    std::string web_dir;              ///< viewer's static files, "" = the build's
};

/// The failure every command throws (common.hpp).
using Failure = scene_render::Failure;

/// Adds the `html` subcommand, filling `options` when parsed.
CLI::App* add(CLI::App& app, Options& options);

/// Reads and checks every input, builds the folder's files in memory, then writes them; throws
/// Failure.
int run(const Options& options);

}  // namespace scene_render::html_command
