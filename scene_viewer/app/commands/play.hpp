#pragma once

/// `play`: a drive (a sequence index and its entity files) rendered frame by frame to
/// numbered PNGs, with track trails, optionally to an MP4 (Debian's ffmpeg, found at run time)
/// at the drive's frame rate and to a strip of frames side by side.

#include <string>

#include "common.hpp"

namespace scene_render {

struct PlayArgs {
    std::string input;        ///< sequence index, or a folder with sequence.json
    std::string out_dir;      ///< --out-dir: <frame>.png per frame
    std::string video;        ///< --video: MP4 path; empty: none
    std::string strip;        ///< --strip: PNG of frames side by side; empty: none
    int strip_frames = 4;     ///< --strip-frames: frames in the strip, evenly spaced
    int trail = 20;           ///< --trail: past positions drawn per track, 0 = none
    double fps = 0.0;         ///< --fps: video frame rate; 0: the index's, else 10
    std::string backgrounds;  ///< --backgrounds: folder of <frame>.png under the camera view
    float opacity = 0.6f;     ///< --backgrounds: opacity of the render
    ViewArgs view;            ///< view, size, shading and model flags
};

CLI::App* add_play_command(CLI::App& app, PlayArgs& args);

/// Renders and writes; throws Failure. Every output (the frames' PNGs, the strip, the video) is
/// staged and committed together after the last frame: a failure leaves the output paths as
/// they were before the run.
int run_play(const PlayArgs& args);

}  // namespace scene_render
