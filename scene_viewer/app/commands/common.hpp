#pragma once

/// What every scene-render command shares: the failure type the error boundary in main.cpp
/// prints, the view flags, reading the inputs and starting the GPU.

#include <memory>
#include <optional>
#include <string>

#include <CLI/CLI.hpp>

#include "scene_schema/entities.hpp"
#include "scene_viewer/assets/class_table.hpp"
#include "scene_viewer/assets/point_cloud.hpp"
#include "scene_viewer/gfx/gl_device.hpp"
#include "scene_viewer/platform/headless_context.hpp"
#include "scene_viewer/render/scene_renderer.hpp"

namespace scene_render {

inline constexpr const char* kTool = "scene-render";

/// A failure: the file or flag at fault, what failed, the detail, and the exit code.
struct Failure {
    std::string what;
    std::string detail;
    std::string where;
    int code = 1;
};

/// Throws a usage Failure (exit code 2) naming the flag.
[[noreturn]] void usage(const std::string& detail, const std::string& flag);

/// View, size, shading and model flags shared by the single render and the grid figure.
struct ViewArgs {
    std::string view = "camera";
    std::string size;
    std::string eye;
    std::string target;
    std::optional<float> fov_deg;
    std::string shading = "lit";
    std::string antialias;    ///< empty: fxaa, or msaa when --msaa is given
    std::optional<int> msaa;  ///< --msaa, when given
    bool no_grid = false;
    bool no_ego = false;
    bool boxes = false;
    std::string classes;
    std::string cloud;
    float point_size = 2.0f;
};

void add_view_options(CLI::App& app, ViewArgs& a);

/// "WxH" from `flag`, or a usage Failure.
std::pair<int, int> size_flag(const std::string& text, const std::string& flag);

/// Checks, before any work, that an output folder can be made or written: an existing path must
/// be a directory, and the nearest existing folder above a new one must be writable. Throws a
/// Failure (exit 1) naming the folder.
void check_output_folder(const std::string& folder, const std::string& what);

/// Reads and validates an entity file, or a Failure naming it: read_entity_text, then
/// parse_entity_text, then entities_from_json.
scene_schema::EntityDocument read_entities(const std::string& path);

/// The text of an entity file ("-": standard input), or a Failure naming it.
std::string read_entity_text(const std::string& path);

/// The text (`path`'s) as JSON, or a Failure naming the file and where the text breaks.
nlohmann::json parse_entity_text(const std::string& text, const std::string& path);

/// The JSON of entity file `path` (`bytes` long) as a validated document, or a Failure naming
/// the file and pointer.
scene_schema::EntityDocument entities_from_json(const nlohmann::json& json, const std::string& path,
                                                std::size_t bytes);

/// Render options from the flags; the camera view and default size come from `document`, read
/// from `document_path` (blamed, exit 1, when its camera size cannot be rendered).
scene_viewer::RenderOptions render_options(const ViewArgs& a,
                                           const scene_schema::EntityDocument& document,
                                           const std::string& document_path);

/// The --cloud overlay, when given.
std::optional<scene_viewer::PointCloud> read_cloud(const ViewArgs& a);

/// The class table (--classes, else the bundled one), none with --boxes.
std::optional<scene_viewer::ClassTable> read_classes(bool boxes, const std::string& classes);

/// The GL context, device and renderer, made after every input was validated.
struct Gpu {
    scene_viewer::HeadlessContext context;
    std::unique_ptr<scene_viewer::Device> device = scene_viewer::make_gl_device();
    scene_viewer::SceneRenderer renderer{*device};
};

/// Starts headless GL and loads the class models, or a Failure.
std::unique_ptr<Gpu> start_gpu(const std::optional<scene_viewer::ClassTable>& classes);

/// One warning per class, per run, for classes drawn as boxes for want of a model.
void warn_boxes(const scene_viewer::SceneRenderer& renderer, const scene_viewer::ClassTable& table);

/// Writes a PNG (or stdout for "-"), or a Failure naming the path.
void write_png_output(const std::string& path, const scene_viewer::ImageRgba8& image);

}  // namespace scene_render
