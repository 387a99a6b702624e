// scene-render: renders entity files headless (see docs/cli.md). Parses the flags, runs one
// command (each in app/commands/), and is the tool's only error boundary.
#include <iostream>
#include <new>
#include <string>
#include <vector>

#include <CLI/CLI.hpp>

#include "commands/bench.hpp"
#include "commands/common.hpp"
#include "commands/grid.hpp"
#include "commands/html_command.hpp"
#include "commands/info.hpp"
#include "commands/play.hpp"
#include "commands/render.hpp"
#include "commands/sensors.hpp"
#include "stereoscene/support/command_table.hpp"
#include "stereoscene/support/error_line.hpp"
#include "stereoscene/support/limit_flags.hpp"
#include "stereoscene/support/process.hpp"

namespace {

using namespace scene_render;
using stereoscene::support::Command;
using stereoscene::support::make_command;

/// The subcommands; without one, scene-render renders (the top-level flags).
std::vector<Command> command_table(CLI::App& app) {
    return {
        make_command<GridArgs>(app, add_grid_command,
                               [](GridArgs& a, CLI::App&) { return run_grid(a); }),
        make_command<BenchArgs>(app, add_bench_command,
                                [](BenchArgs& a, CLI::App&) { return run_bench(a); }),
        make_command<SensorsArgs>(app, add_sensors_command,
                                  [](SensorsArgs& a, CLI::App&) { return run_sensors(a); }),
        make_command<PlayArgs>(app, add_play_command,
                               [](PlayArgs& a, CLI::App&) { return run_play(a); }),
        make_command<html_command::Options>(
            app, html_command::add,
            [](html_command::Options& o, CLI::App&) { return html_command::run(o); }),
    };
}

int run(int argc, char** argv) {
    CLI::App app{"scene-render: renders entity files (KITTI camera frame) headless with OpenGL"};
    app.set_version_flag("--version", std::string(kTool) + " " + STEREOSCENE_VERSION);
    app.require_subcommand(0, 1);

    RenderArgs render;
    add_render_options(app, render);
    bool info = false;
    app.add_flag("--info", info, "print the GL vendor, renderer and version, then exit");
    add_view_options(app, render.view);
    const std::vector<Command> table = command_table(app);
    stereoscene::support::LimitFlags limit_flags;
    stereoscene::support::add_limit_flags(app, limit_flags, true);
    for (const Command& c : table) stereoscene::support::add_limit_flags(*c.sub, limit_flags, true);

    try {
        app.parse(argc, argv);
    } catch (const CLI::ParseError& e) {
        if (e.get_exit_code() == 0) return app.exit(e);  // --help, --version
        usage(e.what(), "see --help");
    }
    stereoscene::support::apply_limit_flags(limit_flags);

    if (info) return run_info();
    if (const Command* c = stereoscene::support::parsed_command(table)) return c->run();
    return run_render(render);
}

}  // namespace

int main(int argc, char** argv) {
    stereoscene::support::keep_freed_memory();
    using stereoscene::support::error_line;
    try {
        return run(argc, argv);
    } catch (const Failure& f) {
        std::cerr << error_line(kTool, f.where, f.what + ": " + f.detail) << "\n";
        return f.code;
    } catch (const std::bad_alloc&) {
        // The readers name the file they were reading; this is what is left.
        std::cerr << error_line(kTool, argc > 1 ? argv[1] : "",
                                "out of memory (std::bad_alloc): the inputs need more memory "
                                "than this machine gives")
                  << "\n";
        return 1;
    } catch (const std::exception& e) {
        std::cerr << error_line(kTool, "", std::string("rendering failed: ") + e.what()) << "\n";
        return 1;
    }
}
