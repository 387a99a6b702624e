#include "render.hpp"

#include <optional>
#include <string_view>
#include <vector>

#include "scene_viewer/assets/image_io.hpp"
#include "scene_viewer/assets/scene_export.hpp"
#include "scene_viewer/render/render_setup.hpp"
#include "stereoscene/support/atomic_file.hpp"

namespace scene_render {

using namespace scene_viewer;

void add_render_options(CLI::App& app, RenderArgs& a) {
    app.add_option("input", a.input, "entity file (JSON, schema 1.x)");
    app.add_option("-o,--output", a.output, "output PNG, '-' for stdout");
    app.add_option("--glb,--export-glb", a.glb,
                   "also export the scene's entities as one binary glTF (.glb); the same "
                   "whatever --view");
    app.add_flag("--glb-ego", a.glb_ego,
                 "--glb: add the ego car (as the chase and bev views draw it, under the camera)");
    app.add_option("--background", a.background,
                   "camera view: lay the render over this image (e.g. the left image)");
    app.add_option("--opacity", a.opacity, "--background: opacity of the render, 0..1")
        ->capture_default_str();
}

namespace {

std::optional<ImageRgba8> read_background(const RenderArgs& a, RenderOptions& options) {
    if (a.background.empty()) return std::nullopt;
    if (options.view.kind != ViewKind::camera) usage("needs --view camera", "--background");
    options.keep_alpha = true;
    try {
        return decode_image(a.background);
    } catch (const std::exception& e) {
        throw Failure{"cannot read background image", e.what(), "--background"};
    }
}

/// The .glb of the document's entities (and the ego car on request), independent of the view:
/// the scene is assembled for the export with the chase view's helpers, without grid or cloud.
std::vector<unsigned char> scene_glb(SceneRenderer& renderer,
                                     const scene_schema::EntityDocument& document,
                                     const RenderOptions& options, const RenderArgs& a) {
    RenderOptions exported = options;
    exported.view = ViewSpec{};
    exported.view.kind = ViewKind::chase;
    exported.ego = a.glb_ego;
    exported.grid = false;
    try {
        renderer.load(document, nullptr, exported);
        return export_scene_glb_bytes(renderer.placed_models());
    } catch (const std::exception& e) {
        throw Failure{"cannot export the scene", e.what(), a.glb};
    }
}

void write_glb(const std::string& path, const std::vector<unsigned char>& bytes) {
    try {
        stereoscene::support::write_file_atomic(
            path, std::string_view(reinterpret_cast<const char*>(bytes.data()), bytes.size()));
    } catch (const std::exception& e) {
        throw Failure{"cannot write the scene", e.what(), path};
    }
}

}  // namespace

int run_render(const RenderArgs& a) {
    if (a.input.empty()) usage("an entity file is required", "input");
    if (a.output.empty() && a.glb.empty()) usage("an output path is required", "--output/--glb");
    const auto document = read_entities(a.input);
    RenderOptions options = render_options(a.view, document);
    if (!(a.opacity >= 0.0f && a.opacity <= 1.0f)) usage("must be in 0..1", "--opacity");
    const std::optional<ImageRgba8> background = read_background(a, options);
    const auto cloud = read_cloud(a.view);
    const auto classes = read_classes(a.view.boxes, a.view.classes);

    if (a.glb_ego && a.glb.empty()) usage("needs --glb", "--glb-ego");
    auto gpu = start_gpu(classes);
    // Everything is built in memory before the first file is written.
    std::vector<unsigned char> glb_bytes;
    if (!a.glb.empty()) glb_bytes = scene_glb(gpu->renderer, document, options, a);
    gpu->renderer.load(document, cloud ? &*cloud : nullptr, options);
    if (classes) warn_boxes(gpu->renderer, *classes);
    if (!a.output.empty()) {
        ImageRgba8 image = gpu->renderer.render_frame();
        if (background) composite_background(image, *background, a.opacity, options.shading);
        write_png_output(a.output, image);
    }
    if (!a.glb.empty()) write_glb(a.glb, glb_bytes);
    return 0;
}

}  // namespace scene_render
