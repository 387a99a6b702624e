#include "info.hpp"

#include <exception>
#include <iostream>

#include "common.hpp"

namespace scene_render {

int run_info() {
    try {
        scene_viewer::HeadlessContext context;
        const scene_viewer::GlInfo info = context.info();
        std::cout << "GL vendor:   " << info.vendor << "\nGL renderer: " << info.renderer
                  << "\nGL version:  " << info.version << "\nEGL platform: " << info.egl_platform
                  << "\n";
    } catch (const std::exception& e) {
        throw Failure{"cannot start headless OpenGL", e.what(), "EGL"};
    }
    return 0;
}

}  // namespace scene_render
