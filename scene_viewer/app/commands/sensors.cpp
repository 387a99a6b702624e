#include "sensors.hpp"

#include "scene_schema/sequence.hpp"
#include "stereoscene/support/atomic_file.hpp"
#include "stereoscene/support/file_read.hpp"

#include <cerrno>
#include <cstring>
#include <fstream>
#include <map>
#include <sstream>
#include <stdexcept>

namespace scene_render {

using namespace scene_viewer;

CLI::App* add_sensors_command(CLI::App& app, SensorsArgs& a) {
    CLI::App* s = app.add_subcommand(
        "sensors",
        "render a stereo rig's view of a scene in a KITTI-like folder (see docs/cli.md)");
    SensorOptions& o = a.options;
    s->add_option("input", a.input, "entity file: the scene (KITTI camera frame)")->required();
    s->add_option("--out", a.out, "output folder (KITTI layout)")->required();
    s->add_option("--frame", a.frame, "frame name of the files")->capture_default_str();
    s->add_option("--seed", o.sensor.seed, "seed of the sensor noise")->capture_default_str();
    CLI::Option* rig =
        s->add_option("--rig", a.rig,
                      "rig from a KITTI calib_cam_to_cam.txt (P_rect_02, P_rect_03, S_rect_02); "
                      "default: the file's frame.camera, else KITTI's");
    s->add_option("--preset", a.preset,
                  "a named rig: kitti, cityscapes, argoverse (5 MP), zed or realsense "
                  "(docs/cli.md); the camera height stays the scene's")
        ->check(CLI::IsMember(rig_preset_names()))
        ->excludes(rig);
    s->add_option("--fx", a.fx_px, "focal length in pixels (fx = fy; after --size)")
        ->check(CLI::PositiveNumber);
    s->add_option("--size", a.size,
                  "image size WxH; the intrinsics scale with it (default: the file's "
                  "frame.camera, else KITTI's 1242x375)");
    s->add_option("--baseline", a.baseline_m,
                  "stereo baseline in metres (default: the file's, else 0.54)");
    s->add_option("--camera-height", o.rig.camera_height_m,
                  "camera above the road in metres (ground underlay)")
        ->capture_default_str();
    s->add_option("--noise", o.sensor.noise_sigma,
                  "Gaussian noise, standard deviation in 8-bit levels")
        ->capture_default_str();
    s->add_option("--blur", o.sensor.blur_sigma_px, "Gaussian blur, standard deviation in pixels")
        ->capture_default_str();
    s->add_option("--right-gain", o.sensor.right_gain,
                  "gain of the right camera relative to the left")
        ->capture_default_str();
    s->add_flag("--vignetting", o.sensor.vignetting, "darken the corners of both images");
    s->add_option("--msaa", o.msaa_samples, "colour images: multisample count, 0 = off")
        ->capture_default_str();
    s->add_option("--label-bleed", o.label_bleed_px,
                  "semantic image: thing borders grown or shrunk by up to N px (seeded by "
                  "--seed, like hand-drawn labels; the instance image stays exact)")
        ->capture_default_str();
    s->add_option("--paints", a.paints,
                  "vehicles' paint in the colour images: class (the class colour) or world "
                  "(white, black, grey, silver... in the shares of the world's cars, each "
                  "vehicle's drawn from its id and --seed; docs/models.md)")
        ->check(CLI::IsMember({"class", "world"}))
        ->capture_default_str();
    s->add_flag("--no-ground", a.no_ground, "no terrain underlay under the road level");
    s->add_flag("--boxes", a.boxes, "draw every entity as a box (no glTF models)");
    s->add_option("--frames", a.frames,
                  "render a drive of N frames named 0000000000.. (entities move by their "
                  "velocity), with truth/<frame>.json and truth/sequence.json");
    s->add_option("--fps", a.drive.fps, "frame rate of a drive, Hz")->capture_default_str();
    s->add_option("--ego-speed", a.drive.ego.speed_mps,
                  "--frames: the camera drives at this speed along its heading, m/s (the scene "
                  "is the world, the camera at the first frame); truth/poses.txt holds its poses")
        ->capture_default_str();
    s->add_option("--ego-yaw-rate", a.drive.ego.yaw_rate_dps,
                  "--frames: the camera turns at this rate, degrees a second (+ right)")
        ->capture_default_str();
    s->add_flag("--resume", a.resume,
                "--frames: keep the frames whose files are all there (each file is written "
                "whole, so a killed run leaves them whole) and render the rest");
    s->add_option("--classes", a.classes,
                  "class table (default: assets/classes/render_classes.json)");
    return s;
}

namespace {

/// The rig: the document's (or KITTI's), replaced by --rig or --preset, then resized, its
/// focal length and baseline replaced.
StereoRig resolve_rig(const SensorsArgs& a, const scene_schema::EntityDocument& document) {
    StereoRig rig = rig_for(document, a.options.rig);
    if (!a.rig.empty()) {
        std::string text;
        try {
            text = stereoscene::support::read_text_input(a.rig);
        } catch (const stereoscene::support::FileError& e) {
            throw Failure{"cannot read rig", e.reason(), a.rig};
        }
        try {
            const double height = rig.camera_height_m;
            rig = parse_kitti_calib(text);
            rig.camera_height_m = height;
        } catch (const std::invalid_argument& e) {
            throw Failure{"invalid rig", e.what(), a.rig};
        }
    }
    if (!a.preset.empty()) rig = rig_preset(a.preset, rig);
    if (!a.size.empty()) {
        const auto [w, h] = size_flag(a.size, "--size");
        rig = rig.resized(w, h);
    }
    if (a.fx_px) rig.fx_px = rig.fy_px = *a.fx_px;
    if (a.baseline_m) rig.baseline_m = *a.baseline_m;
    return rig;
}

/// Renders and writes a drive frame by frame: a failure leaves every earlier frame complete.
int run_drive(SensorsArgs& a, const scene_schema::EntityDocument& scene, Gpu& gpu) {
    const auto index = drive_index(scene.frame.id, a.drive);
    for (const auto& f : index.frames) {
        const std::string name = drive_frame_name(static_cast<int>(f.index));
        if (a.resume) {
            std::vector<std::string> names = kitti_layout_names(name);
            names.push_back("truth/" + f.file);
            if (files_complete(a.out, names)) continue;
        }
        const auto truth = scene_at(scene, *f.timestamp_s, name, a.drive.ego);
        std::map<std::string, std::string> files;
        try {
            files = kitti_layout_files(render_stereo_frame(gpu.renderer, truth, a.options), name);
            files["truth/" + f.file] = scene_schema::dump_checked(truth);
        } catch (const std::exception& e) {
            throw Failure{"cannot render the sensors", "frame " + name + ": " + e.what(), a.input};
        }
        try {
            write_files(a.out, files);
        } catch (const std::exception& e) {
            throw Failure{"cannot write the sensor files", e.what(), a.out};
        }
    }
    try {
        scene_schema::write_sequence_file(index,
                                          std::filesystem::path(a.out) / "truth" / "sequence.json");
        if (a.drive.ego.moving()) {
            std::vector<std::array<double, 12>> poses;
            for (const auto& f : index.frames) poses.push_back(a.drive.ego.pose_at(*f.timestamp_s));
            stereoscene::support::write_file_atomic(
                std::filesystem::path(a.out) / "truth" / "poses.txt",
                scene_schema::format_kitti_poses(poses));
        }
    } catch (const std::exception& e) {
        throw Failure{"cannot write the sensor files", e.what(), a.out};
    }
    return 0;
}

}  // namespace

int run_sensors(SensorsArgs a) {
    const auto document = read_entities(a.input);
    a.options.rig = resolve_rig(a, document);
    a.options.ground_underlay = !a.no_ground;
    a.options.vehicle_paints = a.paints == "world";
    try {
        a.options.validate();
    } catch (const std::invalid_argument& e) {
        usage(e.what(), "sensors");
    }
    try {
        check_frame_name(a.frame);
    } catch (const std::invalid_argument& e) {
        usage(e.what(), "--frame");
    }
    if (a.frames) {
        a.drive.frames = *a.frames;
        try {
            a.drive.validate();
        } catch (const std::invalid_argument& e) {
            usage(e.what(), "sensors");
        }
    } else if (a.resume) {
        usage("only with --frames (a drive)", "--resume");
    } else if (a.drive.ego.moving()) {
        usage("only with --frames (a drive)", "--ego-speed/--ego-yaw-rate");
    }
    const auto classes = read_classes(a.boxes, a.classes);
    auto gpu = start_gpu(classes);
    if (a.frames) return run_drive(a, document, *gpu);
    std::map<std::string, std::string> files;
    try {
        files =
            kitti_layout_files(render_stereo_frame(gpu->renderer, document, a.options), a.frame);
    } catch (const std::invalid_argument& e) {
        throw Failure{"cannot render the sensors", e.what(), a.input};
    }
    try {
        write_files(a.out, files);
    } catch (const std::exception& e) {
        throw Failure{"cannot write the sensor files", e.what(), a.out};
    }
    return 0;
}

}  // namespace scene_render
