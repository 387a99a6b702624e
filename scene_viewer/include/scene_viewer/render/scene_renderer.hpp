#pragma once

/// Renders entity documents: builds the ECS world from a document, runs the systems in their
/// fixed order (build -> transforms -> camera -> render) and reads the image back. One renderer
/// keeps its device, uploaded models and world across frames, so a process renders many frames.

#include <map>
#include <memory>
#include <set>
#include <string>
#include <vector>

#include "scene_schema/entities.hpp"
#include "scene_viewer/assets/colours.hpp"
#include "scene_viewer/assets/model.hpp"
#include "scene_viewer/assets/palette.hpp"
#include "scene_viewer/assets/point_cloud.hpp"
#include "scene_viewer/assets/scene_export.hpp"
#include "scene_viewer/ecs/render_options.hpp"
#include "scene_viewer/ecs/world.hpp"
#include "scene_viewer/gfx/device.hpp"
#include "scene_viewer/gfx/model_library.hpp"
#include "scene_viewer/views/views.hpp"

namespace scene_viewer {

class SceneRenderer {
  public:
    /// Uses `device` (which must outlive the renderer); uploads the box model.
    explicit SceneRenderer(Device& device);

    /// Draws entities of `class_name` with `model` (fitted to each box) instead of a box; with
    /// `low`, only those whose box is lower than it is long or wide (RenderClass::low_model).
    void set_class_model(const std::string& class_name, const Model& model, bool low = false);

    /// Builds the world for a document (and an optional cloud overlay): the build system.
    void load(const scene_schema::EntityDocument& document, const PointCloud* cloud,
              const RenderOptions& options);

    /// Runs transforms -> camera -> render on the loaded world and reads the image back.
    ImageRgba8 render_frame();

    /// load() then render_frame().
    ImageRgba8 render(const scene_schema::EntityDocument& document, const PointCloud* cloud,
                      const RenderOptions& options);

    /// Window depth of the last frame (semantic or instance shading: no MSAA), row 0 at the top.
    std::vector<float> read_depth() { return device_->read_depth(); }

    const World& world() const { return world_; }
    const ModelLibrary& models() const { return models_; }

    /// Names of the loaded document's classes that are drawn as boxes for want of a model
    /// (ground classes excluded: they are patches by design).
    std::set<std::string> classes_drawn_as_boxes() const;

    /// The loaded scene as glTF instances for export_scene_glb(): every entity (and the ego car)
    /// with its model (class model, or a box in the class colour) and its world matrix in the
    /// OpenGL frame (+Y up, metres). Grid and point cloud are not part of it. Valid until the
    /// next load() or set_class_model().
    std::vector<PlacedModel> placed_models();

  private:
    Device* device_;
    ModelLibrary models_;
    World world_;
    RenderOptions options_;
    /// CPU copies of the class models by library key (class_model_key()), for export.
    std::map<std::string, Model> class_models_;
    std::map<std::string, Model> export_boxes_;  ///< box models by class name, for export
};

struct ClassTable;

/// Loads the glTF model of every class of `table` that names one and hands it to `renderer`;
/// returns how many were loaded. Throws the loader's "<file>: <reason>" error.
std::size_t use_class_models(SceneRenderer& renderer, const ClassTable& table);

}  // namespace scene_viewer
