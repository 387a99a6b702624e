#pragma once

#include "scene_viewer/ecs/world.hpp"

namespace scene_viewer {

/// Camera system: computes view and projection of every Camera from its ViewSpec and size.
void update_cameras(World& world);

}  // namespace scene_viewer
