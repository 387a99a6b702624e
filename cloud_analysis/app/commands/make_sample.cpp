#include "make_sample.hpp"

#include <vector>

#include <scene_schema/entities.hpp>

#include "cloud_analysis/io/io.hpp"
#include "output.hpp"

namespace cloud_analysis::app {

CLI::App* add_make_sample_command(CLI::App& app, SampleArgs& args) {
    CLI::App* sample = app.add_subcommand(
        "make-sample",
        "render the synthetic street scene (stereo pair, semantics, calibration, "
        "ground truth) into a folder");
    sample->add_option("--out", args.out, "output folder")->required();
    sample->add_option("--seed", args.options.seed, "texture seed")->capture_default_str();
    sample->add_option("--width", args.options.width_px, "image width, px")->capture_default_str();
    sample->add_option("--height", args.options.height_px, "image height, px")
        ->capture_default_str();
    sample->add_option("--fx", args.options.fx_px, "focal length, px")->capture_default_str();
    return sample;
}

int run_make_sample(const SampleArgs& a) {
    const cloud_analysis::SyntheticScene s = cloud_analysis::make_synthetic_scene(a.options);
    std::filesystem::create_directories(a.out);
    // Everything is encoded first, then written.
    const std::vector<PendingOutput> outputs = {
        {(a.out / "left.png").string(), cloud_analysis::encode_png(s.left), "left"},
        {(a.out / "right.png").string(), cloud_analysis::encode_png(s.right), "right"},
        {(a.out / "semantic.png").string(), cloud_analysis::encode_png(s.semantic), "semantic"},
        {(a.out / "disparity_gt.png").string(),
         cloud_analysis::encode_kitti_disparity_png(s.disparity), "disparity"},
        {(a.out / "calib.yaml").string(), cloud_analysis::synthetic_calibration_yaml(s.camera),
         "calibration"},
        {(a.out / "truth.json").string(), scene_schema::dump(s.truth), "truth"},
    };
    for (const auto& o : outputs) write_output(o);
    return 0;
}

}  // namespace cloud_analysis::app
