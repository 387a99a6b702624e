#include "scene_viewer/systems/transform_system.hpp"

#include "scene_viewer/render/coordinates.hpp"

namespace scene_viewer {

void update_world_matrices(World& world) {
    const auto& owners = world.meshes.owners();
    const auto& meshes = world.meshes.dense();
    for (std::size_t i = 0; i < meshes.size(); ++i) {
        const EntityId e = owners[i];
        const MeshRef& mesh = meshes[i];
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
    }
}

}  // namespace scene_viewer
