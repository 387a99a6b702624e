#pragma once

// The one headless GL context and device of the test executable, shared by every GL test file
// (made on first use, destroyed in reverse order at exit), so test order does not matter.

#include <memory>

#include "scene_viewer/gfx/gl_device.hpp"
#include "scene_viewer/platform/headless_context.hpp"

namespace scene_viewer::testing {

struct Gl {
    HeadlessContext context;
    std::unique_ptr<Device> device = make_gl_device();
};

inline Gl& gl() {
    static Gl instance;
    return instance;
}

inline Device& gl_device() { return *gl().device; }

}  // namespace scene_viewer::testing
