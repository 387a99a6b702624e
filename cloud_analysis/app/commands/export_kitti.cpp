#include "export_kitti.hpp"

#include <iostream>
#include <optional>
#include <stdexcept>
#include <vector>

#include <scene_schema/entities.hpp>

#include "cloud_analysis/evaluation/kitti_labels.hpp"
#include "cloud_analysis/stereo/calibration.hpp"
#include "output.hpp"

namespace cloud_analysis::app {

namespace fs = std::filesystem;

CLI::App* add_export_kitti_command(CLI::App& app, ExportKittiArgs& args) {
    CLI::App* sub = app.add_subcommand(
        "export-kitti",
        "Write an entity file as KITTI object label_2 lines (locations in rectified camera 0, y = "
        "box bottom, alpha, 2D box from the camera; stuff classes are skipped) so KITTI's tools "
        "can score it");
    sub->add_option("entities", args.entities, "entity JSON file")->required();
    sub->add_option("-o,--output", args.output, "label_2 text file ('-' = stdout)")->required();
    sub->add_option("--calib", args.calib,
                    "calibration (KITTI or YAML/JSON): the camera of the 2D boxes and where it "
                    "sits in camera 0 (t of P2); default: the entity file's frame.camera and "
                    "source.calibration");
    return sub;
}

int run_export_kitti(const ExportKittiArgs& args) {
    require_input_files({args.entities, args.calib}, "export");
    if (args.output != "-") {
        const fs::path folder = fs::path(args.output).parent_path();
        if (!folder.empty() && !fs::is_directory(folder)) {
            throw std::runtime_error("cannot export: no such folder (" + folder.string() + ", -o)");
        }
    }
    const scene_schema::EntityDocument doc = scene_schema::read_file(args.entities);
    std::optional<scene_schema::CameraIntrinsics> camera = doc.frame.camera;
    std::optional<LabelFrame> frame = label_frame_of(doc);
    if (!args.calib.empty()) {
        const Calibration calibration = load_calibration(args.calib);
        frame = label_frame_of(calibration);
        const StereoCamera& c = calibration.camera;
        scene_schema::CameraIntrinsics k;
        k.width_px = c.width_px > 0 ? c.width_px : (camera ? camera->width_px : 0);
        k.height_px = c.height_px > 0 ? c.height_px : (camera ? camera->height_px : 0);
        k.fx_px = c.fx_px;
        k.fy_px = c.fy_px;
        k.cx_px = c.cx_px;
        k.cy_px = c.cy_px;
        k.baseline_m = c.baseline_m;
        camera = k;
    }
    if (!frame) {
        std::cerr << kTool << ": warning: " << args.entities.string()
                  << ": the file does not say where its camera sits in KITTI's camera 0: "
                     "locations are written in its own camera's frame (give --calib)\n";
    }
    if (!camera) {
        std::cerr << kTool << ": warning: " << args.entities.string()
                  << ": no camera (frame.camera or --calib): 2D boxes are -1, which KITTI's "
                     "evaluation ignores\n";
    }
    std::vector<KittiLabel> labels;
    for (const auto& e : doc.entities) {
        if (!kitti_type_of_class(e.class_name)) continue;
        labels.push_back(
            kitti_label_from_entity(e, camera ? &*camera : nullptr, frame.value_or(LabelFrame{})));
    }
    const std::string text = format_kitti_labels(labels);
    if (args.output == "-") {
        std::cout << text;
    } else {
        stereoscene::support::write_file_atomic(args.output, text);
    }
    return 0;
}

}  // namespace cloud_analysis::app
