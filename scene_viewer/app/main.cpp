// scene-render: renders entity files headless (see docs/cli.md).
#include <CLI/CLI.hpp>

int main(int argc, char** argv) {
    CLI::App app{"scene-render: render entity files headless"};
    try {
        app.parse(argc, argv);
    } catch (const CLI::ParseError& e) {
        return app.exit(e) == 0 ? 0 : 2;
    }
    return 0;
}
