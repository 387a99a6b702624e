// cloud-analysis: stereo pair + calibration + semantic image -> disparity, labelled metric
// cloud (.xyz/.pcd/.ply) and entity file. Thin CLI: parse, validate, call the library, write;
// one file per command under commands/.

#include <algorithm>
#include <csignal>
#include <iostream>
#include <new>
#include <string>
#include <vector>

#include <CLI/CLI.hpp>
#include <stereoscene/support/error_line.hpp>
#include <stereoscene/support/limit_flags.hpp>
#include <stereoscene/support/process.hpp>

#include "commands/analyse.hpp"
#include "commands/batch.hpp"
#include "commands/bench.hpp"
#include "commands/evaluate.hpp"
#include "commands/evaluate_odometry.hpp"
#include "commands/evaluate_tracks.hpp"
#include "commands/export_kitti.hpp"
#include "commands/make_sample.hpp"
#include "commands/output.hpp"
#include "commands/report.hpp"
#include "commands/score_semantics.hpp"
#include "commands/track.hpp"

namespace {

using cloud_analysis::app::kTool;

bool is_subcommand(const std::string& arg) {
    return arg == "analyse" || arg == "evaluate" || arg == "export-kitti" || arg == "make-sample" ||
           arg == "batch" || arg == "bench" || arg == "report" || arg == "score-semantics" ||
           arg == "track" || arg == "evaluate-tracks" || arg == "evaluate-odometry" ||
           arg == "help";
}

}  // namespace

int main(int argc, char** argv) {
    namespace app_ = cloud_analysis::app;
    stereoscene::support::keep_freed_memory();
    std::signal(SIGPIPE, SIG_IGN);  // a closed stdout becomes a write error with a message
    // `analyse` is the default command: insert it unless a subcommand or --version is first.
    std::vector<std::string> args(argv + 1, argv + argc);
    if (args.empty() || (!is_subcommand(args[0]) && args[0] != "--version")) {
        args.insert(args.begin(), "analyse");
    }
    if (!args.empty() && args[0] == "help") args = {"--help"};
    const std::string command = args.empty() ? std::string() : args[0];
    std::reverse(args.begin(), args.end());  // CLI11 parses a reversed vector

    CLI::App app{
        "cloud-analysis: rectified stereo pair + calibration + semantic image -> "
        "disparity, labelled metric point cloud and entity file.\n"
        "Commands: analyse (default), evaluate, export-kitti, make-sample, batch, report, bench, "
        "score-semantics, track, evaluate-tracks, evaluate-odometry. Exit codes: 0 ok, 1 failure, "
        "2 usage, 3 "
        "(evaluate) a bar was missed."};
    app.set_version_flag("--version", std::string(kTool) + " " + STEREOSCENE_VERSION);
    app.require_subcommand(0, 1);
    app_::AnalyseArgs analyse_args;
    CLI::App* analyse = app_::add_analyse_command(app, analyse_args);
    app_::EvaluateArgs evaluate_args;
    CLI::App* evaluate = app_::add_evaluate_command(app, evaluate_args);
    app_::ExportKittiArgs export_args;
    CLI::App* export_kitti = app_::add_export_kitti_command(app, export_args);
    app_::BatchArgs batch_args;
    CLI::App* batch = app_::add_batch_command(app, batch_args);
    app_::ReportArgs report_args;
    CLI::App* report = app_::add_report_command(app, report_args);
    app_::BenchArgs bench_args;
    CLI::App* bench = app_::add_bench_command(app, bench_args);
    app_::SampleArgs sample_args;
    CLI::App* sample = app_::add_make_sample_command(app, sample_args);
    app_::ScoreSemanticsArgs score_args;
    CLI::App* score = app_::add_score_semantics_command(app, score_args);
    app_::TrackArgs track_args;
    CLI::App* track = app_::add_track_command(app, track_args);
    app_::EvaluateTracksArgs evaluate_tracks_args;
    CLI::App* evaluate_tracks = app_::add_evaluate_tracks_command(app, evaluate_tracks_args);
    app_::EvaluateOdometryArgs evaluate_odometry_args;
    CLI::App* evaluate_odometry = app_::add_evaluate_odometry_command(app, evaluate_odometry_args);
    stereoscene::support::LimitFlags limit_flags;
    for (CLI::App* sub : app.get_subcommands([](CLI::App*) { return true; })) {
        stereoscene::support::add_limit_flags(*sub, limit_flags, false);
    }

    try {
        app.parse(args);
        stereoscene::support::apply_limit_flags(limit_flags);
        if (*sample) return app_::run_make_sample(sample_args);
        if (*analyse) {
            app_::resolve(analyse_args, *analyse);
            return app_::run_analyse(analyse_args);
        }
        if (*batch) {
            app_::resolve_batch(batch_args, *batch);
            return app_::run_batch(batch_args);
        }
        if (*report) return app_::run_report(report_args);
        if (*bench) {
            app_::resolve(bench_args.analyse, *bench);
            return app_::run_bench(bench_args);
        }
        if (*evaluate) return app_::run_evaluate(evaluate_args);
        if (*export_kitti) return app_::run_export_kitti(export_args);
        if (*score) return app_::run_score_semantics(score_args);
        if (*track) return app_::run_track(track_args);
        if (*evaluate_tracks) return app_::run_evaluate_tracks(evaluate_tracks_args);
        if (*evaluate_odometry) return app_::run_evaluate_odometry(evaluate_odometry_args);
        std::cout << app.help();
        return 0;
    } catch (const CLI::ParseError& e) {
        if (e.get_exit_code() == 0) return app.exit(e);  // --help, --version
        std::cerr << kTool << ": error: usage: " << e.what() << " (see --help)\n";
        return 2;
    } catch (const std::bad_alloc&) {
        // The readers name the file they were reading; this is what is left.
        std::cerr << stereoscene::support::error_line(
                         kTool, command,
                         "out of memory (std::bad_alloc): the inputs need more memory than this "
                         "machine gives")
                  << "\n";
        return 1;
    } catch (const std::exception& e) {
        std::cerr << stereoscene::support::error_line(kTool, e.what()) << "\n";
        return 1;
    }
}
