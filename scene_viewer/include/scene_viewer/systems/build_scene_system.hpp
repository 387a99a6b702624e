#pragma once

#include <string>

#include "scene_schema/entities.hpp"
#include "scene_viewer/assets/point_cloud.hpp"
#include "scene_viewer/ecs/world.hpp"
#include "scene_viewer/gfx/model_library.hpp"

namespace scene_viewer {

struct RenderOptions;

/// The model library key of a class's model ("class:car"), or of its model for boxes lower than
/// they are long or wide ("class:vegetation:low", RenderClass::low_model).
std::string class_model_key(const std::string& class_name, bool low = false);

/// Build system: clears `world` and creates one entity per document entity (Transform, MeshRef,
/// Material, SourceEntity), ground classes as flat patches, the ego car, the BEV grid, the point
/// cloud overlay and the camera. Uploads the grid and cloud meshes into `models`.
void build_scene(World& world, const scene_schema::EntityDocument& document,
                 const PointCloud* cloud, const RenderOptions& options, ModelLibrary& models);

}  // namespace scene_viewer
