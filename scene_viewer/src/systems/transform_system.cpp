#include "scene_viewer/systems/transform_system.hpp"

#include "scene_viewer/ecs/coordinates.hpp"

namespace scene_viewer {

void update_world_matrices(World& world) {
    // Every mesh gets a world matrix: helpers without a Transform (grid, cloud) are already in
    // world metres and take the frame change alone.
    const auto place = [&](EntityId e, const MeshRef& mesh) {
        const Transform* t = world.transforms.get(e);
        glm::mat4 m = gl_from_kitti();
        if (mesh.fit_to_transform && t != nullptr) {
            m = box_world_matrix(t->centre_kitti, t->theta_rad, t->size_whl) * mesh.fit;
        }
        if (WorldMatrix* w = world.world_matrices.get(e)) {
            w->value = m;
        } else {
            world.world_matrices.set(e, WorldMatrix{m});
        }
    };
    for_each(place, world.meshes);
}

}  // namespace scene_viewer
