// cloud-analysis: stereo pair + calibration + semantic image -> disparity, labelled metric
// cloud (.xyz/.pcd/.ply) and entity file. Thin CLI: parse, validate, call the library, write.

#include <algorithm>
#include <csignal>
#include <iostream>
#include <string>
#include <vector>

#include <CLI/CLI.hpp>
#include <scene_schema/entities.hpp>
#include <stereoscene/support/process.hpp>

#include "analyse_command.hpp"
#include "cloud_analysis/io/io.hpp"
#include "cloud_analysis/synthetic/synthetic.hpp"
#include "evaluate_command.hpp"
#include "perf_commands.hpp"
#include "score_semantics_command.hpp"

namespace {

using cloud_analysis::app::kTool;
using cloud_analysis::app::PendingOutput;
using cloud_analysis::app::write_output;

/// Flags of `make-sample`.
struct SampleArgs {
    std::filesystem::path out;
    cloud_analysis::SyntheticOptions options;
};

/// Renders the synthetic scene and writes the bundled sample's files into a folder.
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

bool is_subcommand(const std::string& arg) {
    return arg == "analyse" || arg == "evaluate" || arg == "export-kitti" || arg == "make-sample" ||
           arg == "batch" || arg == "bench" || arg == "report" || arg == "score-semantics" ||
           arg == "help";
}

}  // namespace

int main(int argc, char** argv) {
    stereoscene::support::keep_freed_memory();
    std::signal(SIGPIPE, SIG_IGN);  // a closed stdout becomes a write error with a message
    // `analyse` is the default command: insert it unless a subcommand or --version is first.
    std::vector<std::string> args(argv + 1, argv + argc);
    if (args.empty() || (!is_subcommand(args[0]) && args[0] != "--version")) {
        args.insert(args.begin(), "analyse");
    }
    if (!args.empty() && args[0] == "help") args = {"--help"};
    std::reverse(args.begin(), args.end());  // CLI11 parses a reversed vector

    CLI::App app{
        "cloud-analysis: rectified stereo pair + calibration + semantic image -> "
        "disparity, labelled metric point cloud and entity file.\n"
        "Commands: analyse (default), evaluate, export-kitti, make-sample, batch, report, bench, "
        "score-semantics. Exit "
        "codes: 0 ok, 1 "
        "failure, 2 usage, 3 (evaluate) a bar was missed."};
    app.set_version_flag("--version", std::string(kTool) + " " + STEREOSCENE_VERSION);
    app.require_subcommand(0, 1);
    cloud_analysis::app::AnalyseArgs analyse_args;
    CLI::App* analyse = app.add_subcommand(
        "analyse", "stereo pair -> disparity -> cloud -> entities (the default command)");
    cloud_analysis::app::add_input_flags(*analyse, analyse_args);
    cloud_analysis::app::add_settings_flags(*analyse, analyse_args);
    cloud_analysis::app::add_output_flags(*analyse, analyse_args);
    analyse->footer(
        "Other commands: evaluate, export-kitti, make-sample, batch, report, bench (each with "
        "--help).\n"
        "Exit codes: 0 ok, 1 failure (one line on stderr, no output written), 2 usage error.");
    cloud_analysis::app::EvaluateArgs evaluate_args;
    CLI::App* evaluate = cloud_analysis::app::add_evaluate_command(app, evaluate_args);
    cloud_analysis::app::ExportKittiArgs export_args;
    CLI::App* export_kitti = cloud_analysis::app::add_export_kitti_command(app, export_args);

    cloud_analysis::app::BatchArgs batch_args;
    CLI::App* batch = cloud_analysis::app::add_batch_command(app, batch_args);
    cloud_analysis::app::ReportArgs report_args;
    CLI::App* report = cloud_analysis::app::add_report_command(app, report_args);
    cloud_analysis::app::BenchArgs bench_args;
    CLI::App* bench = cloud_analysis::app::add_bench_command(app, bench_args);

    cloud_analysis::app::ScoreSemanticsArgs score_args;
    CLI::App* score = cloud_analysis::app::add_score_semantics_command(app, score_args);

    SampleArgs sample_args;
    CLI::App* sample = app.add_subcommand(
        "make-sample",
        "render the synthetic street scene (stereo pair, semantics, calibration, "
        "ground truth) into a folder");
    sample->add_option("--out", sample_args.out, "output folder")->required();
    sample->add_option("--seed", sample_args.options.seed, "texture seed")->capture_default_str();
    sample->add_option("--width", sample_args.options.width_px, "image width, px")
        ->capture_default_str();
    sample->add_option("--height", sample_args.options.height_px, "image height, px")
        ->capture_default_str();
    sample->add_option("--fx", sample_args.options.fx_px, "focal length, px")
        ->capture_default_str();

    try {
        app.parse(args);
        if (*sample) return run_make_sample(sample_args);
        if (*analyse) {
            cloud_analysis::app::resolve(analyse_args, *analyse);
            return cloud_analysis::app::run_analyse(analyse_args);
        }
        if (*batch) {
            cloud_analysis::app::resolve_batch(batch_args, *batch);
            return cloud_analysis::app::run_batch(batch_args);
        }
        if (*report) return cloud_analysis::app::run_report(report_args);
        if (*bench) {
            cloud_analysis::app::resolve(bench_args.analyse, *bench);
            return cloud_analysis::app::run_bench(bench_args);
        }
        if (*evaluate) return cloud_analysis::app::run_evaluate(evaluate_args);
        if (*export_kitti) return cloud_analysis::app::run_export_kitti(export_args);
        if (*score) return cloud_analysis::app::run_score_semantics(score_args);
        std::cout << app.help();
        return 0;
    } catch (const CLI::ParseError& e) {
        if (e.get_exit_code() == 0) return app.exit(e);  // --help, --version
        std::cerr << kTool << ": error: usage: " << e.what() << " (see --help)\n";
        return 2;
    } catch (const std::exception& e) {
        std::cerr << kTool << ": error: " << e.what() << "\n";
        return 1;
    }
}
