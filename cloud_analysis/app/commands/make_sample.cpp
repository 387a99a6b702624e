#include "make_sample.hpp"

#include <filesystem>
#include <stdexcept>
#include <system_error>
#include <vector>

#include <scene_schema/entities.hpp>
#include <stereoscene/support/output_transaction.hpp>

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
    try {
        a.options.validate();
    } catch (const std::invalid_argument& e) {
        throw CLI::ValidationError("--width/--height", e.what());
    }
    const cloud_analysis::SyntheticScene s = cloud_analysis::make_synthetic_scene(a.options);
    // The folder is made only for the write below, and removed again if that fails.
    std::error_code ec;
    const bool made_folder = std::filesystem::create_directories(a.out, ec);
    if (ec) {
        throw std::runtime_error("cannot write output: " + ec.message() + " (" + a.out.string() +
                                 ")");
    }
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
    try {
        stereoscene::support::OutputTransaction files;
        for (const auto& o : outputs) files.stage(o.path, o.bytes, o.sync);
        files.commit();
    } catch (const stereoscene::support::FileError& e) {
        if (made_folder) std::filesystem::remove(a.out, ec);
        throw std::runtime_error("cannot write output: " + e.reason() + " (" + e.path().string() +
                                 ")");
    }
    return 0;
}

}  // namespace cloud_analysis::app
