#include "scene_viewer/render/scene_renderer.hpp"

#include <algorithm>
#include <stdexcept>

#include "scene_viewer/assets/class_table.hpp"
#include "scene_viewer/assets/gltf_loader.hpp"
#include "scene_viewer/assets/palette.hpp"
#include "scene_viewer/systems/build_scene_system.hpp"
#include "scene_viewer/systems/camera_system.hpp"
#include "scene_viewer/systems/render_system.hpp"
#include "scene_viewer/systems/transform_system.hpp"

namespace scene_viewer {

SceneRenderer::SceneRenderer(Device& device) : device_(&device), models_(device) {
    models_.put("box", unit_box_mesh());
}

void SceneRenderer::set_class_model(const std::string& class_name, const Model& model, bool low) {
    const std::string key = class_model_key(class_name, low);
    models_.put(key, model);
    class_models_[key] = model;
}

void SceneRenderer::load(const scene_schema::EntityDocument& document, const PointCloud* cloud,
                         const RenderOptions& options) {
    options.validate();
    options_ = options;
    build_scene(world_, document, cloud, options_, models_);
}

ImageRgba8 SceneRenderer::render_frame() {
    update_world_matrices(world_);
    update_cameras(world_);
    FrameSetup setup;
    const bool lit = options_.shading == Shading::lit;
    const Rgb8 bg = lit                                     ? kLitBackground
                    : options_.shading == Shading::semantic ? kSemanticBackground
                                                            : Rgb8{0, 0, 0};
    setup.clear_colour = {bg[0] / 255.0f, bg[1] / 255.0f, bg[2] / 255.0f, 0.0f};
    setup.msaa_samples = lit && options_.antialias == Antialias::msaa ? options_.msaa_samples : 0;
    setup.fxaa = lit && options_.antialias == Antialias::fxaa;
    setup.texture_frame = options_.texture_frame;
    render_world(world_, models_, *device_, setup);
    ImageRgba8 image = device_->read_pixels();
    if (!options_.keep_alpha) {
        for (std::size_t i = 3; i < image.pixels.size(); i += 4) image.pixels[i] = 255;
    }
    return image;
}

std::set<std::string> SceneRenderer::classes_drawn_as_boxes() const {
    std::set<std::string> names;
    const auto collect = [&](EntityId, const MeshRef& mesh, const SourceEntity& source) {
        if (source.index < 0 || is_ground_class(source.class_id, source.class_name)) return;
        if (models_.at(mesh.model).key == "box") names.insert(source.class_name);
    };
    for_each(collect, world_.meshes, world_.sources);
    return names;
}

std::vector<PlacedModel> SceneRenderer::placed_models() {
    update_world_matrices(world_);
    std::vector<PlacedModel> placed;
    const auto place = [&](EntityId, const MeshRef& mesh, const SourceEntity& source,
                           const WorldMatrix& world_matrix) {
        if (!mesh.fit_to_transform) return;
        const std::string& key = models_.at(mesh.model).key;
        const Model* model = nullptr;
        if (const auto own = class_models_.find(key); own != class_models_.end()) {
            model = &own->second;
        } else {
            auto box = export_boxes_.find(source.class_name);
            if (box == export_boxes_.end()) {
                const Rgb8 colour = class_colour(source.class_id, source.class_name);
                box =
                    export_boxes_.emplace(source.class_name, make_box_model(linear_colour(colour)))
                        .first;
            }
            model = &box->second;
        }
        placed.push_back(PlacedModel{model, world_matrix.value, source.id});
    };
    for_each(place, world_.meshes, world_.sources, world_.world_matrices);
    return placed;
}

ImageRgba8 SceneRenderer::render(const scene_schema::EntityDocument& document,
                                 const PointCloud* cloud, const RenderOptions& options) {
    load(document, cloud, options);
    return render_frame();
}

std::size_t use_class_models(SceneRenderer& renderer, const ClassTable& table) {
    std::size_t loaded = 0;
    for (const RenderClass& c : table.classes) {
        if (c.model.empty() || c.kind == RenderKind::Ground) continue;
        renderer.set_class_model(c.name, load_model(c.model));
        ++loaded;
        if (!c.low_model.empty()) {
            renderer.set_class_model(c.name, load_model(c.low_model), true);
            ++loaded;
        }
    }
    return loaded;
}

}  // namespace scene_viewer
