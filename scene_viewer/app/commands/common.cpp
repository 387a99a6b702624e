#include "common.hpp"

#include "scene_schema/json_text.hpp"

#include <unistd.h>

#include <cerrno>
#include <cstdint>
#include <cstring>
#include <fstream>
#include <iostream>
#include <new>
#include <set>
#include <sstream>
#include <stdexcept>

#include "scene_viewer/assets/palette.hpp"
#include "scene_viewer/render/image.hpp"
#include "scene_viewer/render/render_setup.hpp"
#include "stereoscene/support/atomic_file.hpp"
#include "stereoscene/support/file_read.hpp"
#include "stereoscene/support/limits.hpp"

namespace scene_render {

using namespace scene_viewer;

void usage(const std::string& detail, const std::string& flag) {
    throw Failure{"bad usage", detail, flag, 2};
}

void add_view_options(CLI::App& app, ViewArgs& a) {
    app.add_option("--view", a.view, "camera | chase | bev | free")->capture_default_str();
    app.add_option("--size", a.size,
                   "image size WxH in pixels (default: camera view: the frame's camera size, else "
                   "1242x375; bev: 800x800; chase/free: 1280x720)");
    app.add_option("--eye", a.eye, "free/chase view: eye x,y,z in metres (KITTI camera frame)");
    app.add_option("--target", a.target, "free/chase view: look-at point x,y,z in metres");
    app.add_option("--fov", a.fov_deg, "free/chase view: vertical field of view in degrees");
    app.add_option("--shading", a.shading, "lit | semantic | instance")->capture_default_str();
    app.add_option("--antialias", a.antialias,
                   "lit shading: fxaa | msaa | none (default: fxaa; msaa when --msaa is given)");
    app.add_option("--msaa", a.msaa, "lit shading: multisample count (default 4), 0 = off");
    app.add_flag("--no-grid", a.no_grid, "bev view: no metre grid");
    app.add_flag("--no-ego", a.no_ego, "chase/bev/free views: do not draw the ego car");
    app.add_flag("--boxes", a.boxes, "draw every entity as a box (no glTF models)");
    app.add_option("--classes", a.classes,
                   "class table (default: assets/classes/render_classes.json)");
    app.add_option("--cloud", a.cloud, "point cloud overlay (.ply, .pcd, .xyz)");
    app.add_option("--point-size", a.point_size, "point cloud overlay: point size in pixels")
        ->capture_default_str();
}

namespace {

/// Sets o.antialias and o.msaa_samples from --antialias and --msaa (alone, it implies msaa);
/// rejects contradictory combinations (--msaa N > 1 with fxaa or none, --antialias msaa with
/// --msaa 0 or 1) and antialiasing asked of unlit shading. Needs o.shading.
void apply_antialias(const std::string& name, std::optional<int> msaa, RenderOptions& o) {
    if (!name.empty()) {
        try {
            o.antialias = parse_antialias(name);
        } catch (const std::invalid_argument& e) {
            usage(e.what(), "--antialias");
        }
        if (o.shading != Shading::lit && o.antialias != Antialias::none)
            usage("applies to lit shading only (semantic and instance colours stay exact)",
                  "--antialias");
    }
    if (!msaa) return;
    if (!name.empty() && o.antialias != Antialias::msaa) {
        if (*msaa > 1) usage("multisampling contradicts --antialias " + name, "--msaa");
        return;
    }
    if (!name.empty() && *msaa < 2) usage("--antialias msaa needs 2..16 samples", "--msaa");
    o.antialias = Antialias::msaa;
    o.msaa_samples = *msaa;
}

glm::vec3 point_flag(const std::string& text, const std::string& flag) {
    try {
        return parse_point_m(text);
    } catch (const std::invalid_argument& e) {
        usage(e.what(), flag);
    }
}

/// --view into o.view (chase starts from its own pose).
void apply_view_kind(const ViewArgs& a, RenderOptions& o) {
    try {
        o.view.kind = parse_view_kind(a.view);
    } catch (const std::invalid_argument& e) {
        usage(e.what(), "--view");
    }
    if (o.view.kind == ViewKind::chase) o.view = chase_view();
}

/// --eye, --target and --fov into o.view; only the free and chase views take them.
void apply_pose(const ViewArgs& a, RenderOptions& o) {
    const bool posed = o.view.kind == ViewKind::free || o.view.kind == ViewKind::chase;
    if ((!a.eye.empty() || !a.target.empty() || a.fov_deg) && !posed) {
        usage("needs --view free or chase", !a.eye.empty()      ? "--eye"
                                            : !a.target.empty() ? "--target"
                                                                : "--fov");
    }
    if (!a.eye.empty()) o.view.eye_kitti = point_flag(a.eye, "--eye");
    if (!a.target.empty()) o.view.target_kitti = point_flag(a.target, "--target");
    if (a.fov_deg) o.view.fov_y_deg = *a.fov_deg;
}

}  // namespace

std::pair<int, int> size_flag(const std::string& text, const std::string& flag) {
    std::pair<int, int> size;
    try {
        size = parse_image_size(text);
    } catch (const std::invalid_argument& e) {
        usage(e.what(), flag);
    }
    const auto pixels = static_cast<std::uint64_t>(size.first) * size.second;
    const std::uint64_t limit = stereoscene::support::limits().max_image_pixels;
    if (pixels > limit) {
        usage(std::to_string(pixels) + " pixels is more than the limit of " +
                  std::to_string(limit) + "; " + stereoscene::support::kPixelsHint,
              flag);
    }
    return size;
}

void check_output_folder(const std::string& folder, const std::string& what) {
    namespace fs = std::filesystem;
    std::error_code ec;
    const fs::path path = fs::absolute(folder, ec);
    if (ec) throw Failure{what, ec.message(), folder};
    if (fs::exists(path, ec)) {
        if (!fs::is_directory(path, ec)) throw Failure{what, "exists and is not a folder", folder};
        if (::access(path.c_str(), W_OK) != 0) {
            throw Failure{what, std::string("not writable: ") + std::strerror(errno), folder};
        }
        return;
    }
    fs::path above = path.parent_path();
    while (!above.empty() && !fs::exists(above, ec) && above != above.root_path()) {
        above = above.parent_path();
    }
    if (!fs::is_directory(above, ec)) {
        throw Failure{what, above.string() + " is not a folder", folder};
    }
    if (::access(above.c_str(), W_OK) != 0) {
        throw Failure{what, above.string() + " is not writable: " + std::strerror(errno), folder};
    }
}

std::string read_entity_text(const std::string& path) {
    try {
        // "-" is standard input, as in `cloud-analysis ... -o - | scene-render - ...`.
        return stereoscene::support::read_text_input(path);
    } catch (const stereoscene::support::FileError& e) {
        throw Failure{"cannot read entity file", e.reason(), path};
    }
}

namespace {

/// Runs `step` on an entity file's text or JSON, its schema errors and running out of memory
/// turned into Failures naming `path`.
template <typename Step>
auto entity_step(Step step, const std::string& path, std::size_t bytes) {
    try {
        return step();
    } catch (const scene_schema::SchemaError& e) {
        const std::string pointer = e.pointer().empty() ? "(document)" : e.pointer();
        throw Failure{"invalid entity file", pointer + ": " + e.rule(), path};
    } catch (const std::bad_alloc&) {
        throw Failure{"cannot read entity file",
                      "out of memory reading its " + std::to_string(bytes) + " bytes of JSON",
                      path};
    }
}

}  // namespace

nlohmann::json parse_entity_text(const std::string& text, const std::string& path) {
    return entity_step([&] { return scene_schema::parse_json(text); }, path, text.size());
}

scene_schema::EntityDocument entities_from_json(const nlohmann::json& json, const std::string& path,
                                                std::size_t bytes) {
    return entity_step([&] { return scene_schema::from_json(json); }, path, bytes);
}

scene_schema::EntityDocument read_entities(const std::string& path) {
    const std::string text = read_entity_text(path);
    return entities_from_json(parse_entity_text(text, path), path, text.size());
}

namespace {

/// Refuses an image size that came from the entity file's camera (no --size) when the renderer
/// cannot draw it while the flags alone could: the file is at fault (exit 1), not the flags.
void check_document_size(const RenderOptions& o, const std::string& problem,
                         const std::string& document_path) {
    RenderOptions small = o;
    small.width_px = small.height_px = 1;
    try {
        small.validate();
    } catch (const std::invalid_argument&) {
        return;  // the flags are at fault too: a usage error names them
    }
    throw Failure{"cannot render the entity file's camera image",
                  "/frame/camera: " + std::to_string(o.width_px) + "x" +
                      std::to_string(o.height_px) + ": " + problem + " (give --size)",
                  document_path};
}

}  // namespace

RenderOptions render_options(const ViewArgs& a, const scene_schema::EntityDocument& document,
                             const std::string& document_path) {
    RenderOptions o;
    apply_view_kind(a, o);
    try {
        o.shading = parse_shading(a.shading);
    } catch (const std::invalid_argument& e) {
        usage(e.what(), "--shading");
    }
    std::tie(o.width_px, o.height_px) =
        a.size.empty() ? default_image_size(o.view.kind, document) : size_flag(a.size, "--size");
    apply_pose(a, o);
    apply_antialias(a.antialias, a.msaa, o);
    o.grid = !a.no_grid;
    o.ego = !a.no_ego;
    o.point_size_px = a.point_size;
    if (a.size.empty()) {
        const auto pixels = static_cast<std::uint64_t>(o.width_px) * o.height_px;
        const std::uint64_t limit = stereoscene::support::limits().max_image_pixels;
        if (pixels > limit) {
            check_document_size(o,
                                "too large: " + std::to_string(pixels) +
                                    " pixels is more than the limit of " + std::to_string(limit),
                                document_path);
        }
    }
    try {
        o.validate();
    } catch (const std::invalid_argument& e) {
        if (a.size.empty()) check_document_size(o, e.what(), document_path);
        usage(e.what(), "--antialias/--msaa/--fov/--eye/--target/--point-size");
    }
    return o;
}

std::optional<PointCloud> read_cloud(const ViewArgs& a) {
    if (a.cloud.empty()) return std::nullopt;
    try {
        return read_point_cloud(a.cloud);
    } catch (const std::exception& e) {
        throw Failure{"cannot read point cloud", e.what(), "--cloud"};
    }
}

std::optional<ClassTable> read_classes(bool boxes, const std::string& classes) {
    if (boxes) return std::nullopt;
    std::filesystem::path path;
    try {
        path = classes.empty() ? default_class_table_path() : std::filesystem::path(classes);
        return load_class_table(path);
    } catch (const std::exception& e) {
        throw Failure{"cannot read class table", e.what(),
                      classes.empty() ? path.string() : "--classes"};
    }
}

std::unique_ptr<Gpu> start_gpu(const std::optional<ClassTable>& classes) {
    std::unique_ptr<Gpu> gpu;
    try {
        gpu = std::make_unique<Gpu>();
    } catch (const std::exception& e) {
        throw Failure{"cannot start headless OpenGL", e.what(), "EGL"};
    }
    if (classes) {
        try {
            use_class_models(gpu->renderer, *classes);
        } catch (const std::exception& e) {
            throw Failure{"cannot load class model", e.what(), classes->source.string()};
        }
    }
    return gpu;
}

void warn_boxes(const SceneRenderer& renderer, const ClassTable& table) {
    static std::set<std::string> warned;
    for (const std::string& name : classes_missing_models(renderer, table)) {
        if (warned.insert(name).second) {
            std::cerr << kTool << ": warning: no model for class '" << name << "', drawn as a box "
                      << (cityscapes_by_name(name)
                              ? "in its class colour"
                              : "in magenta (a class the palette does not know)")
                      << "\n";
        }
    }
}

void write_png_output(const std::string& path, const ImageRgba8& image) {
    try {
        write_png(path, image, 1);
    } catch (const std::exception& e) {
        throw Failure{"cannot write image", e.what(), path};
    }
}

}  // namespace scene_render
