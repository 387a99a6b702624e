#pragma once

#include "scene_schema/entities.hpp"
#include "scene_viewer/assets/point_cloud.hpp"
#include "scene_viewer/ecs/world.hpp"
#include "scene_viewer/gfx/model_library.hpp"

namespace scene_viewer {

struct RenderOptions;

/// Build system: clears `world` and creates one entity per document entity (Transform, MeshRef,
/// Material, SourceEntity), ground classes as flat patches, the ego car, the BEV grid, the point
/// cloud overlay and the camera. Uploads the grid and cloud meshes into `models`.
void build_scene(World& world, const scene_schema::EntityDocument& document,
                 const PointCloud* cloud, const RenderOptions& options, ModelLibrary& models);

}  // namespace scene_viewer
