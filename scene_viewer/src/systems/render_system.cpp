#include "scene_viewer/systems/render_system.hpp"

#include <stdexcept>

namespace scene_viewer {

void render_world(const World& world, const ModelLibrary& models, Device& device,
                  FrameSetup setup) {
    if (world.cameras.size() == 0) throw std::logic_error("render: the world has no camera");
    const Camera& camera = world.cameras.dense().front();
    setup.width_px = camera.width_px;
    setup.height_px = camera.height_px;
    const glm::mat4 view_projection = camera.projection * camera.view;
    device.begin_frame(setup);
    const auto draw = [&](EntityId, const MeshRef& mesh, const Material& material,
                          const WorldMatrix& world_matrix) {
        for (const UploadedPrimitive& p : models.at(mesh.model).primitives) {
            DrawCall call;
            call.mesh = p.mesh;
            call.texture = material.lit ? p.texture : TextureHandle{};
            call.model = world_matrix.value * p.node_transform;
            call.view_projection = view_projection;
            const glm::vec4 base = p.paint && material.painted ? material.paint : p.base_colour;
            call.colour = material.lit ? material.colour * base : material.colour;
            call.lit = material.lit;
            call.vertex_colour = material.vertex_colour;
            call.point_size_px = material.point_size_px;
            call.procedural = material.procedural;
            device.draw(call);
        }
    };
    for_each(draw, world.meshes, world.materials, world.world_matrices);
    device.end_frame();
}

}  // namespace scene_viewer
