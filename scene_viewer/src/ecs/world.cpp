#include "scene_viewer/ecs/world.hpp"

namespace scene_viewer {

EntityId World::create() { return next_++; }

void World::clear() {
    transforms.clear();
    world_matrices.clear();
    meshes.clear();
    materials.clear();
    cameras.clear();
    sources.clear();
    next_ = 0;
}

}  // namespace scene_viewer
