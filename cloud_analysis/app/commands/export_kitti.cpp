#include "export_kitti.hpp"

#include <iostream>
#include <optional>
#include <stdexcept>
#include <vector>

#include <scene_schema/entities.hpp>

#include "cloud_analysis/evaluation/kitti_labels.hpp"
#include "cloud_analysis/stereo/calibration.hpp"

namespace cloud_analysis::app {

namespace fs = std::filesystem;

CLI::App* add_export_kitti_command(CLI::App& app, ExportKittiArgs& args) {
    CLI::App* sub = app.add_subcommand(
        "export-kitti",
        "Write an entity file as KITTI object label_2 lines (y = box bottom, alpha, 2D box "
        "from the camera; stuff classes are skipped) so KITTI's tools can score it");
    sub->add_option("entities", args.entities, "entity JSON file")->required();
    sub->add_option("-o,--output", args.output, "label_2 text file ('-' = stdout)")->required();
    sub->add_option("--calib", args.calib,
                    "calibration (KITTI or YAML/JSON) for the 2D boxes; default: the entity "
                    "file's frame.camera, else 2D boxes are -1");
    return sub;
}

int run_export_kitti(const ExportKittiArgs& args) {
    for (const auto& f : {args.entities, args.calib}) {
        std::error_code ec;
        if (!f.empty() && f != "-" && !fs::is_regular_file(f, ec)) {
            throw std::runtime_error("cannot export: no such file (" + f.string() + ")");
        }
    }
    if (args.output != "-") {
        const fs::path folder = fs::path(args.output).parent_path();
        if (!folder.empty() && !fs::is_directory(folder)) {
            throw std::runtime_error("cannot export: no such folder (" + folder.string() + ", -o)");
        }
    }
    const scene_schema::EntityDocument doc = scene_schema::read_file(args.entities);
    std::optional<scene_schema::CameraIntrinsics> camera = doc.frame.camera;
    if (!args.calib.empty()) {
        const StereoCamera c = load_calibration(args.calib).camera;
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
    std::vector<KittiLabel> labels;
    for (const auto& e : doc.entities) {
        if (!kitti_type_of_class(e.class_name)) continue;
        labels.push_back(kitti_label_from_entity(e, camera ? &*camera : nullptr));
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
