#include "render.hpp"

#include <cerrno>
#include <cstdio>
#include <cstring>
#include <optional>
#include <string_view>
#include <vector>

#include "scene_viewer/assets/image_io.hpp"
#include "scene_viewer/assets/scene_export.hpp"
#include "scene_viewer/render/render_setup.hpp"
#include "stereoscene/support/atomic_file.hpp"
#include "stereoscene/support/output_transaction.hpp"

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

std::string_view as_text(const std::vector<unsigned char>& bytes) {
    return std::string_view(reinterpret_cast<const char*>(bytes.data()), bytes.size());
}

/// Refuses unusable output paths (a directory, the same file twice) before any work.
void declare_outputs(const RenderArgs& a, stereoscene::support::OutputTransaction& outputs) {
    try {
        if (!a.output.empty() && a.output != "-") outputs.declare(a.output, "--output");
        if (!a.glb.empty()) {
            if (a.glb == "-") usage("the .glb cannot go to standard output", "--glb");
            outputs.declare(a.glb, "--glb");
        }
    } catch (const stereoscene::support::FileError& e) {
        throw Failure{"unusable output path", e.reason(), e.path().string()};
    }
}

}  // namespace

int run_render(const RenderArgs& a) {
    if (a.input.empty()) usage("an entity file is required", "input");
    if (a.output.empty() && a.glb.empty()) usage("an output path is required", "--output/--glb");
    const auto document = read_entities(a.input);
    RenderOptions options = render_options(a.view, document, a.input);
    if (!(a.opacity >= 0.0f && a.opacity <= 1.0f)) usage("must be in 0..1", "--opacity");
    stereoscene::support::OutputTransaction outputs;
    declare_outputs(a, outputs);
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
    std::vector<unsigned char> png;
    if (!a.output.empty()) {
        ImageRgba8 image = gpu->renderer.render_frame();
        if (background) composite_background(image, *background, a.opacity, options.shading);
        png = encode_png(image, 1);
    }
    // Both files are staged, then committed together: all of them or none.
    try {
        if (!a.output.empty() && a.output != "-") outputs.stage(a.output, as_text(png));
        if (!a.glb.empty()) outputs.stage(a.glb, as_text(glb_bytes));
        outputs.commit();
    } catch (const stereoscene::support::FileError& e) {
        throw Failure{"cannot write output", e.reason(), e.path().string()};
    }
    if (a.output == "-" && (std::fwrite(png.data(), 1, png.size(), stdout) != png.size() ||
                            std::fflush(stdout) != 0)) {
        throw Failure{"cannot write image", std::strerror(errno), "-"};
    }
    return 0;
}

}  // namespace scene_render
