#pragma once

#include "scene_viewer/ecs/world.hpp"

namespace scene_viewer {

/// Transform system: WorldMatrix = box placement (centre, yaw, W/H/L) x model fit for every
/// entity with a Transform and a MeshRef; meshes already in KITTI metres (grid, cloud) get
/// gl_from_kitti().
void update_world_matrices(World& world);

}  // namespace scene_viewer
