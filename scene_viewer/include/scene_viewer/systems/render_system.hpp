#pragma once

#include "scene_viewer/ecs/world.hpp"
#include "scene_viewer/gfx/device.hpp"
#include "scene_viewer/gfx/model_library.hpp"

namespace scene_viewer {

/// Render system (the thesis's RendererSystem): one frame through the first Camera; every
/// entity with WorldMatrix + MeshRef + Material becomes one draw per model primitive.
/// Throws std::logic_error when the world has no camera.
void render_world(const World& world, const ModelLibrary& models, Device& device, FrameSetup setup);

}  // namespace scene_viewer
