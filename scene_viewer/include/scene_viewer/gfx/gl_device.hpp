#pragma once

/// The OpenGL 4.5 backend. Needs a current context (HeadlessContext) for its whole life.

#include <memory>

#include "scene_viewer/gfx/device.hpp"

namespace scene_viewer {

/// Compiles the shaders and returns the GL device; throws std::runtime_error with the GL
/// compiler log when a shader fails.
std::unique_ptr<Device> make_gl_device();

}  // namespace scene_viewer
