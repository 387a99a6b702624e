#pragma once

/// The default command: one entity file -> one PNG (and/or a .glb of the scene).

#include <string>

#include "common.hpp"

namespace scene_render {

struct RenderArgs {
    std::string input;       ///< entity file
    std::string output;      ///< PNG path, "-" for stdout; empty: none
    std::string glb;         ///< .glb path of the assembled scene; empty: none
    bool glb_ego = false;    ///< --glb-ego: the ego car in the .glb too
    std::string background;  ///< camera view: image the render is laid over; empty: none
    float opacity = 0.6f;    ///< --background: opacity of the render, 0..1
    ViewArgs view;           ///< view, size, shading and model flags
};

/// Adds the render flags but the view flags (add_view_options) to the top-level app: rendering
/// is the default command.
void add_render_options(CLI::App& app, RenderArgs& args);

/// Renders args.input; throws Failure.
int run_render(const RenderArgs& args);

}  // namespace scene_render
