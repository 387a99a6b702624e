#pragma once

/// `sensors`: a stereo rig's view of a scene, written as a KITTI-like folder.

#include <optional>
#include <string>

#include "common.hpp"
#include "scene_viewer/sensors/drive.hpp"
#include "scene_viewer/sensors/stereo_sensors.hpp"

namespace scene_render {

struct SensorsArgs {
    std::string input;                    ///< entity file: the scene (KITTI camera frame)
    std::string out;                      ///< output folder (KITTI layout)
    std::string frame = "000000";         ///< frame name of the files
    std::string rig;                      ///< KITTI calib_cam_to_cam.txt; empty: the file's camera
    std::string size;                     ///< image size WxH; empty: the rig's
    std::string preset;                   ///< a named rig (rig_preset); empty: none
    std::optional<double> fx_px;          ///< focal length (fx = fy), px; none: the rig's
    std::optional<double> baseline_m;     ///< stereo baseline, metres; none: the rig's
    bool no_ground = false;               ///< no terrain underlay under the road level
    std::string paints = "class";         ///< --paints: "class" or "world" (vehicle_paints)
    bool boxes = false;                   ///< boxes instead of glTF models
    std::string classes;                  ///< class table; empty: the bundled one
    scene_viewer::SensorOptions options;  ///< noise, blur, gain, vignetting, MSAA, seed
    std::optional<int> frames;            ///< a drive of this many frames; none: one frame
    scene_viewer::DriveOptions drive;     ///< frame rate of a drive
    bool resume = false;                  ///< --resume: a drive's complete frames are kept
};

CLI::App* add_sensors_command(CLI::App& app, SensorsArgs& args);

/// Renders and writes the frame's files; throws Failure.
int run_sensors(SensorsArgs args);

}  // namespace scene_render
