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
#include <stereoscene/support/command_table.hpp>
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
using stereoscene::support::Command;
using stereoscene::support::make_command;

/// The commands, in the order the help lists them; `analyse` is the default.
std::vector<Command> command_table(CLI::App& app) {
    namespace a = cloud_analysis::app;
    return {
        make_command<a::AnalyseArgs>(app, a::add_analyse_command,
                                     [](a::AnalyseArgs& args, CLI::App& sub) {
                                         a::resolve(args, sub);
                                         return a::run_analyse(args);
                                     }),
        make_command<a::EvaluateArgs>(
            app, a::add_evaluate_command,
            [](a::EvaluateArgs& args, CLI::App&) { return a::run_evaluate(args); }),
        make_command<a::ExportKittiArgs>(
            app, a::add_export_kitti_command,
            [](a::ExportKittiArgs& args, CLI::App&) { return a::run_export_kitti(args); }),
        make_command<a::SampleArgs>(
            app, a::add_make_sample_command,
            [](a::SampleArgs& args, CLI::App&) { return a::run_make_sample(args); }),
        make_command<a::BatchArgs>(app, a::add_batch_command,
                                   [](a::BatchArgs& args, CLI::App& sub) {
                                       a::resolve_batch(args, sub);
                                       return a::run_batch(args);
                                   }),
        make_command<a::ReportArgs>(
            app, a::add_report_command,
            [](a::ReportArgs& args, CLI::App&) { return a::run_report(args); }),
        make_command<a::BenchArgs>(app, a::add_bench_command,
                                   [](a::BenchArgs& args, CLI::App& sub) {
                                       a::resolve(args.analyse, sub);
                                       return a::run_bench(args);
                                   }),
        make_command<a::ScoreSemanticsArgs>(
            app, a::add_score_semantics_command,
            [](a::ScoreSemanticsArgs& args, CLI::App&) { return a::run_score_semantics(args); }),
        make_command<a::TrackArgs>(
            app, a::add_track_command,
            [](a::TrackArgs& args, CLI::App&) { return a::run_track(args); }),
        make_command<a::EvaluateTracksArgs>(
            app, a::add_evaluate_tracks_command,
            [](a::EvaluateTracksArgs& args, CLI::App&) { return a::run_evaluate_tracks(args); }),
        make_command<a::EvaluateOdometryArgs>(app, a::add_evaluate_odometry_command,
                                              [](a::EvaluateOdometryArgs& args, CLI::App&) {
                                                  return a::run_evaluate_odometry(args);
                                              }),
    };
}

}  // namespace

int main(int argc, char** argv) {
    stereoscene::support::keep_freed_memory();
    std::signal(SIGPIPE, SIG_IGN);  // a closed stdout becomes a write error with a message
    CLI::App app;
    app.set_version_flag("--version", std::string(kTool) + " " + STEREOSCENE_VERSION);
    app.require_subcommand(0, 1);
    const std::vector<Command> table = command_table(app);
    app.description(
        "cloud-analysis: rectified stereo pair + calibration + semantic image -> disparity, "
        "labelled metric point cloud and entity file.\nCommands: " +
        stereoscene::support::command_names(table) +
        " (analyse is the default; help lists the flags). Exit codes: 0 ok, 1 failure, 2 usage, "
        "3 (evaluate) a bar was missed.");
    stereoscene::support::LimitFlags limit_flags;
    for (const Command& c : table)
        stereoscene::support::add_limit_flags(*c.sub, limit_flags, false);

    // `analyse` is the default command: insert it unless a command or --version is first.
    std::vector<std::string> args(argv + 1, argv + argc);
    if (args.empty() || (!stereoscene::support::is_command(table, args[0]) && args[0] != "help" &&
                         args[0] != "--version")) {
        args.insert(args.begin(), "analyse");
    }
    if (args[0] == "help") args = {"--help"};
    const std::string command = args[0];
    std::reverse(args.begin(), args.end());  // CLI11 parses a reversed vector

    try {
        app.parse(args);
        stereoscene::support::apply_limit_flags(limit_flags);
        if (const Command* c = stereoscene::support::parsed_command(table)) return c->run();
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
