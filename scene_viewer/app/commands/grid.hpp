#pragma once

/// `grid`: several entity files rendered with one camera into a labelled figure.

#include <string>
#include <vector>

#include "common.hpp"

namespace scene_render {

struct GridArgs {
    std::vector<std::string> inputs;  ///< entity files, one tile each
    std::vector<std::string> labels;  ///< one label per input; empty: the file names
    std::string output;               ///< PNG path, "-" for stdout
    int columns = 0;                  ///< tiles per row; 0: square-ish
    ViewArgs view;                    ///< view, size, shading and model flags
};

CLI::App* add_grid_command(CLI::App& app, GridArgs& args);

/// Renders the figure; throws Failure.
int run_grid(GridArgs args);

}  // namespace scene_render
