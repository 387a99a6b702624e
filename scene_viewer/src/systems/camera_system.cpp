#include "scene_viewer/systems/camera_system.hpp"

#include "scene_viewer/views/views.hpp"

namespace scene_viewer {

void update_cameras(World& world) {
    for (Camera& camera : world.cameras.dense()) {
        const ViewMatrices m = view_matrices(camera.spec, camera.width_px, camera.height_px);
        camera.view = m.view;
        camera.projection = m.projection;
    }
}

}  // namespace scene_viewer
