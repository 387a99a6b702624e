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
#include "scene_viewer/assets/model.hpp"
#include "scene_viewer/assets/scene_export.hpp"
#include "scene_viewer/ecs/world.hpp"
#include "scene_viewer/gfx/device.hpp"
#include "scene_viewer/render/model_library.hpp"
#include "scene_viewer/render/palette.hpp"
#include "scene_viewer/render/point_cloud.hpp"
#include "scene_viewer/views/views.hpp"

namespace scene_viewer {

enum class Shading {
    lit,       ///< directional + ambient light, class colours, antialiased (RenderOptions)
    semantic,  ///< exact palette colours, no lighting, no MSAA (pixel-checkable)
    instance,  ///< flat (labelId, instance, 0) / 255 per entity, no MSAA (KITTI instance ids)
};

/// "lit" / "semantic" / "instance" -> Shading; throws std::invalid_argument otherwise.
Shading parse_shading(const std::string& name);

/// How lit shading smooths its edges (semantic and instance shading never do).
enum class Antialias {
    fxaa,  ///< FXAA 3.11 pass over the single-sample image (~7 ms at 1280x720 on llvmpipe)
    msaa,  ///< multisampling, RenderOptions::msaa_samples (~25 ms at 4x, 1280x720, llvmpipe)
    none,  ///< hard edges
};

/// "fxaa" / "msaa" / "none" -> Antialias; throws std::invalid_argument otherwise.
Antialias parse_antialias(const std::string& name);

/// Largest accepted image side, pixels.
inline constexpr int kMaxImageSide = 16384;
/// Largest accepted pixels x samples of one frame (2^28: 16384^2 with one single-sample target,
/// about 2 GB of colour and depth; MSAA counts its samples, FXAA's second target 2).
inline constexpr long long kMaxFrameSamples = 1LL << 28;

struct RenderOptions {
    int width_px = 1242;                    ///< image width, pixels, 1..kMaxImageSide
    int height_px = 375;                    ///< image height, pixels, 1..kMaxImageSide
    ViewSpec view;                          ///< camera; camera-view intrinsics come from the file
    bool fit_bev = true;                    ///< bev: frame every entity (ignores bev_* of view)
    Shading shading = Shading::lit;         ///< lit or semantic
    Antialias antialias = Antialias::fxaa;  ///< lit: edge smoothing; semantic, instance: none
    int msaa_samples = 4;                   ///< lit, Antialias::msaa: multisample count (0 = off)
    bool grid = true;                       ///< bev: draw a 1 m ground grid (10 m lines darker)
    bool ego = true;                        ///< chase/bev/free: draw the ego car at the camera
    float point_size_px = 2.0f;             ///< point cloud overlay: point size, pixels
    bool keep_alpha = false;                ///< keep alpha 0 where nothing was drawn (compositing)
    bool procedural_texture = false;        ///< lit: world-space noise texture on every surface
    /// Throws std::invalid_argument naming the bad field.
    void validate() const;
};

/// Colours that are not classes: background of lit and semantic renders, ego car.
inline constexpr Rgb8 kLitBackground{205, 215, 228};
inline constexpr Rgb8 kSemanticBackground{0, 0, 0};
inline constexpr Rgb8 kLitEgoColour{230, 230, 235};

class SceneRenderer {
  public:
    /// Uses `device` (which must outlive the renderer); uploads the box model.
    explicit SceneRenderer(Device& device);

    /// Draws entities of `class_name` with `model` (fitted to each box) instead of a box.
    void set_class_model(const std::string& class_name, const Model& model);

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
    std::map<std::string, Model> class_models_;  ///< CPU copies of the class models, for export
    std::map<std::string, Model> export_boxes_;  ///< box models by class name, for export
};

struct ClassTable;

/// Loads the glTF model of every class of `table` that names one and hands it to `renderer`;
/// returns how many were loaded. Throws the loader's "<file>: <reason>" error.
std::size_t use_class_models(SceneRenderer& renderer, const ClassTable& table);

}  // namespace scene_viewer
