#include <iostream>

#include <CLI/CLI.hpp>

int main(int argc, char** argv) {
    CLI::App app{"cloud-analysis: stereo pair + semantic image -> metric cloud and entities"};
    app.set_version_flag("--version", std::string("cloud-analysis ") + STEREOSCENE_VERSION);
    try {
        app.parse(argc, argv);
    } catch (const CLI::ParseError& e) {
        return app.exit(e) == 0 ? 0 : 2;
    }
    return 0;
}
