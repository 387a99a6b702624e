// scene-render: renders entity files headless (see docs/cli.md). Parses, validates every input,
// then calls the scene_viewer library; the only error boundary of the tool.
#include <cerrno>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <iostream>
#include <map>
#include <optional>
#include <set>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

#include <CLI/CLI.hpp>

#include "commands/html_command.hpp"
#include "scene_schema/entities.hpp"
#include "scene_viewer/assets/class_table.hpp"
#include "scene_viewer/assets/image_io.hpp"
#include "scene_viewer/figure/grid_figure.hpp"
#include "scene_viewer/gfx/gl_device.hpp"
#include "scene_viewer/platform/headless_context.hpp"
#include "scene_viewer/render/benchmark.hpp"
#include "scene_viewer/render/image.hpp"
#include "scene_viewer/render/scene_renderer.hpp"
#include "scene_viewer/sensors/stereo_sensors.hpp"
#include "stereoscene/support/atomic_file.hpp"
#include "stereoscene/support/error_line.hpp"
#include "stereoscene/support/process.hpp"

namespace {

using namespace scene_viewer;

/// A failure with the parts of the one-line message and the exit code.
struct Failure {
    std::string what;
    std::string detail;
    std::string where;
    int code = 1;
};

[[noreturn]] void usage(const std::string& detail, const std::string& flag) {
    throw Failure{"bad usage", detail, flag, 2};
}

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

glm::vec3 parse_vec3(const std::string& text, const std::string& flag) {
    std::stringstream ss(text);
    glm::vec3 v(0.0f);
    char comma = 0;
    if (!(ss >> v.x >> comma) || comma != ',' || !(ss >> v.y >> comma) || comma != ',' ||
        !(ss >> v.z) || !(ss >> std::ws).eof()) {
        usage("expected x,y,z in metres, got '" + text + "'", flag);
    }
    return v;
}

std::pair<int, int> parse_size(const std::string& text) {
    std::stringstream ss(text);
    long long w = 0, h = 0;
    char x = 0;
    if (!(ss >> w >> x >> h) || (x != 'x' && x != 'X') || !(ss >> std::ws).eof()) {
        usage("expected WxH, got '" + text + "'", "--size");
    }
    if (w < 1 || h < 1 || w > kMaxImageSide || h > kMaxImageSide) {
        usage("each side must be in 1.." + std::to_string(kMaxImageSide) + ", got '" + text + "'",
              "--size");
    }
    return {static_cast<int>(w), static_cast<int>(h)};
}

scene_schema::EntityDocument read_entities(const std::string& path) {
    std::ifstream in(path, std::ios::binary);
    if (!in) throw Failure{"cannot read entity file", std::strerror(errno), path};
    std::stringstream buffer;
    buffer << in.rdbuf();
    try {
        return scene_schema::parse(buffer.str());
    } catch (const scene_schema::SchemaError& e) {
        const std::string pointer = e.pointer().empty() ? "(document)" : e.pointer();
        throw Failure{"invalid entity file", pointer + ": " + e.rule(), path};
    }
}

/// Render options from the flags; the camera view and default size come from `document`.
RenderOptions render_options(const ViewArgs& a, const scene_schema::EntityDocument& document) {
    RenderOptions o;
    try {
        o.view.kind = parse_view_kind(a.view);
    } catch (const std::invalid_argument& e) {
        usage(e.what(), "--view");
    }
    if (o.view.kind == ViewKind::chase) o.view = chase_view();
    try {
        o.shading = parse_shading(a.shading);
    } catch (const std::invalid_argument& e) {
        usage(e.what(), "--shading");
    }
    if (!a.size.empty()) {
        std::tie(o.width_px, o.height_px) = parse_size(a.size);
    } else if (o.view.kind == ViewKind::bev) {
        o.width_px = o.height_px = 800;
    } else if (o.view.kind != ViewKind::camera) {
        o.width_px = 1280;
        o.height_px = 720;
    } else if (document.frame.camera) {
        o.width_px = document.frame.camera->width_px;
        o.height_px = document.frame.camera->height_px;
    }
    const bool posed = o.view.kind == ViewKind::free || o.view.kind == ViewKind::chase;
    if ((!a.eye.empty() || !a.target.empty() || a.fov_deg) && !posed) {
        usage("needs --view free or chase", !a.eye.empty()      ? "--eye"
                                            : !a.target.empty() ? "--target"
                                                                : "--fov");
    }
    if (!a.eye.empty()) o.view.eye_kitti = parse_vec3(a.eye, "--eye");
    if (!a.target.empty()) o.view.target_kitti = parse_vec3(a.target, "--target");
    if (a.fov_deg) o.view.fov_y_deg = *a.fov_deg;
    apply_antialias(a.antialias, a.msaa, o);
    o.grid = !a.no_grid;
    o.ego = !a.no_ego;
    o.point_size_px = a.point_size;
    try {
        o.validate();
    } catch (const std::invalid_argument& e) {
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

std::optional<ClassTable> read_classes(const ViewArgs& a) {
    if (a.boxes) return std::nullopt;
    const std::filesystem::path path =
        a.classes.empty() ? default_class_table_path() : std::filesystem::path(a.classes);
    try {
        return load_class_table(path);
    } catch (const std::exception& e) {
        throw Failure{"cannot read class table", e.what(),
                      a.classes.empty() ? path.string() : "--classes"};
    }
}

/// The GL context, device and renderer, made after every input was validated.
struct Gpu {
    HeadlessContext context;
    std::unique_ptr<Device> device = make_gl_device();
    SceneRenderer renderer{*device};
};

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

/// One warning per class, per run, for classes drawn as boxes for want of a model (classes of
/// kind "block" without a model are boxes by design and do not warn).
void warn_boxes(const SceneRenderer& renderer, const ClassTable& table) {
    static std::set<std::string> warned;
    for (const std::string& name : renderer.classes_drawn_as_boxes()) {
        const RenderClass* c = table.find(std::string_view(name));
        if (c != nullptr && c->kind == RenderKind::Block) continue;
        if (warned.insert(name).second) {
            std::cerr << "scene-render: warning: no model for class '" << name
                      << "', drawn as a box in its class colour\n";
        }
    }
}

void write_output(const std::string& path, const ImageRgba8& image) {
    try {
        write_png(path, image, 1);
    } catch (const std::exception& e) {
        throw Failure{"cannot write image", e.what(), path};
    }
}

int print_info() {
    try {
        HeadlessContext context;
        const GlInfo info = context.info();
        std::cout << "GL vendor:   " << info.vendor << "\nGL renderer: " << info.renderer
                  << "\nGL version:  " << info.version << "\nEGL platform: " << info.egl_platform
                  << "\n";
    } catch (const std::exception& e) {
        throw Failure{"cannot start headless OpenGL", e.what(), "EGL"};
    }
    return 0;
}

int run(int argc, char** argv) {
    CLI::App app{"scene-render: renders entity files (KITTI camera frame) headless with OpenGL"};
    app.set_version_flag("--version", "scene-render 0.1.0");
    app.require_subcommand(0, 1);

    std::string input, output, background, glb;
    float opacity = 0.6f;
    bool info = false;
    ViewArgs view;
    app.add_option("input", input, "entity file (JSON, schema 1.x)");
    app.add_option("-o,--output", output, "output PNG, '-' for stdout");
    app.add_option("--glb,--export-glb", glb,
                   "also export the assembled scene as one binary glTF (.glb)");
    app.add_option("--background", background,
                   "camera view: lay the render over this image (e.g. the left image)");
    app.add_option("--opacity", opacity, "--background: opacity of the render, 0..1")
        ->capture_default_str();
    app.add_flag("--info", info, "print the GL vendor, renderer and version, then exit");
    add_view_options(app, view);

    CLI::App* grid = app.add_subcommand("grid", "render several entity files into a labelled grid");
    std::vector<std::string> grid_inputs, grid_labels;
    std::string grid_output;
    int grid_columns = 0;
    ViewArgs grid_view;
    grid->add_option("--inputs", grid_inputs, "entity files")->required();
    grid->add_option("--labels", grid_labels, "one label per input (default: file names)");
    grid->add_option("-o,--output", grid_output, "output PNG, '-' for stdout")->required();
    grid->add_option("--columns", grid_columns, "tiles per row (default: square-ish)");
    add_view_options(*grid, grid_view);

    CLI::App* bench = app.add_subcommand("bench", "time frames of a synthetic street scene");
    BenchmarkOptions bench_options;
    std::string bench_size = "1280x720";
    int bench_msaa = 4;
    bool bench_boxes = false;
    bench->add_option("--frames", bench_options.frames, "timed frames")->capture_default_str();
    bench->add_option("--entities", bench_options.entity_count, "cars in the scene")
        ->capture_default_str();
    bench->add_option("--size", bench_size, "image size WxH")->capture_default_str();
    bench
        ->add_option("--msaa", bench_msaa,
                     "multisample count of the 'lit msaa' row (0 = no such row)")
        ->capture_default_str();
    bench->add_option("--zlib", bench_options.zlib_level, "PNG zlib level 0..9")
        ->capture_default_str();
    bench->add_flag("--boxes", bench_boxes, "draw boxes instead of glTF models");

    CLI::App* sensors = app.add_subcommand(
        "sensors",
        "render a stereo rig's view of a scene in a KITTI-like folder (see docs/cli.md)");
    std::string sensors_input, sensors_out, sensors_size, sensors_frame = "000000";
    std::string sensors_classes, sensors_rig;
    bool sensors_boxes = false;
    SensorOptions sensor_options;
    std::optional<double> sensors_baseline;
    sensors->add_option("input", sensors_input, "entity file: the scene (KITTI camera frame)")
        ->required();
    sensors->add_option("--out", sensors_out, "output folder (KITTI layout)")->required();
    sensors->add_option("--frame", sensors_frame, "frame name of the files")->capture_default_str();
    sensors->add_option("--seed", sensor_options.sensor.seed, "seed of the sensor noise")
        ->capture_default_str();
    sensors->add_option("--rig", sensors_rig,
                        "rig from a KITTI calib_cam_to_cam.txt (P_rect_02, P_rect_03, S_rect_02); "
                        "default: the file's frame.camera, else KITTI's");
    sensors->add_option("--size", sensors_size,
                        "image size WxH; the intrinsics scale with it (default: the file's "
                        "frame.camera, else KITTI's 1242x375)");
    sensors->add_option("--baseline", sensors_baseline,
                        "stereo baseline in metres (default: the file's, else 0.54)");
    sensors
        ->add_option("--camera-height", sensor_options.rig.camera_height_m,
                     "camera above the road in metres (ground underlay)")
        ->capture_default_str();
    sensors
        ->add_option("--noise", sensor_options.sensor.noise_sigma,
                     "Gaussian noise, standard deviation in 8-bit levels")
        ->capture_default_str();
    sensors
        ->add_option("--blur", sensor_options.sensor.blur_sigma_px,
                     "Gaussian blur, standard deviation in pixels")
        ->capture_default_str();
    sensors
        ->add_option("--right-gain", sensor_options.sensor.right_gain,
                     "gain of the right camera relative to the left")
        ->capture_default_str();
    sensors->add_flag("--vignetting", sensor_options.sensor.vignetting,
                      "darken the corners of both images");
    sensors
        ->add_option("--msaa", sensor_options.msaa_samples,
                     "colour images: multisample count, 0 = off")
        ->capture_default_str();
    bool sensors_no_ground = false;
    sensors->add_flag("--no-ground", sensors_no_ground, "no terrain underlay under the road level");
    sensors->add_flag("--boxes", sensors_boxes, "draw every entity as a box (no glTF models)");
    sensors->add_option("--classes", sensors_classes,
                        "class table (default: assets/classes/render_classes.json)");

    scene_render::html_command::Options html_options;
    CLI::App* html = scene_render::html_command::add(app, html_options);

    try {
        app.parse(argc, argv);
    } catch (const CLI::ParseError& e) {
        if (e.get_exit_code() == 0) return app.exit(e);  // --help, --version
        usage(e.what(), "see --help");
    }

    if (info) return print_info();
    if (*html) return scene_render::html_command::run(html_options);

    if (*bench) {
        RenderOptions o;
        std::tie(o.width_px, o.height_px) = parse_size(bench_size);
        try {
            bench_options.validate();
        } catch (const std::invalid_argument& e) {
            usage(e.what(), "bench");
        }
        if (bench_msaa < 0 || bench_msaa > 16) usage("must be in 0..16", "--msaa");
        ViewArgs classes_args;
        classes_args.boxes = bench_boxes;
        const auto classes = read_classes(classes_args);
        auto gpu = start_gpu(classes);
        const auto document = make_benchmark_document(bench_options.entity_count);
        const GlInfo gl = gpu->context.info();
        std::printf("renderer: %s; scene: %d cars + road and sidewalks, %dx%d, %s, %d frames\n",
                    gl.renderer.c_str(), bench_options.entity_count, o.width_px, o.height_px,
                    bench_boxes ? "boxes" : "glTF models", bench_options.frames);
        std::printf("%-16s %10s %10s %10s %8s %8s %9s\n", "shading", "triangles", "ms/frame",
                    "min ms", "fps", "PNG ms", "PNG KiB");
        struct Config {
            std::string name;
            Shading shading;
            Antialias antialias;
        };
        // The default first, then what it replaces and what it costs over no antialiasing.
        std::vector<Config> configs = {{"lit fxaa", Shading::lit, Antialias::fxaa},
                                       {"lit none", Shading::lit, Antialias::none},
                                       {"semantic", Shading::semantic, Antialias::none}};
        if (bench_msaa > 1) {
            configs.insert(configs.begin() + 1, {"lit msaa " + std::to_string(bench_msaa),
                                                 Shading::lit, Antialias::msaa});
        }
        o.msaa_samples = bench_msaa;
        for (const Config& c : configs) {
            o.shading = c.shading;
            o.antialias = c.antialias;
            const BenchmarkResult r = run_benchmark(gpu->renderer, document, o, bench_options);
            std::printf("%-16s %10zu %10.2f %10.2f %8.1f %8.2f %9.1f\n", c.name.c_str(),
                        r.triangles, r.frame_ms, r.frame_ms_min, r.fps, r.png_ms,
                        static_cast<double>(r.png_bytes) / 1024.0);
        }
        return 0;
    }

    if (*sensors) {
        const auto document = read_entities(sensors_input);
        StereoRig rig = rig_for(document, sensor_options.rig);
        if (!sensors_rig.empty()) {
            std::ifstream in(sensors_rig, std::ios::binary);
            if (!in) throw Failure{"cannot read rig", std::strerror(errno), sensors_rig};
            std::stringstream text;
            text << in.rdbuf();
            try {
                const double height = rig.camera_height_m;
                rig = parse_kitti_calib(text.str());
                rig.camera_height_m = height;
            } catch (const std::invalid_argument& e) {
                throw Failure{"invalid rig", e.what(), sensors_rig};
            }
        }
        if (!sensors_size.empty()) {
            const auto [w, h] = parse_size(sensors_size);
            rig = rig.resized(w, h);
        }
        if (sensors_baseline) rig.baseline_m = *sensors_baseline;
        sensor_options.rig = rig;
        sensor_options.ground_underlay = !sensors_no_ground;
        try {
            sensor_options.validate();
        } catch (const std::invalid_argument& e) {
            usage(e.what(), "sensors");
        }
        try {
            check_frame_name(sensors_frame);
        } catch (const std::invalid_argument& e) {
            usage(e.what(), "--frame");
        }
        ViewArgs classes_args;
        classes_args.boxes = sensors_boxes;
        classes_args.classes = sensors_classes;
        const auto classes = read_classes(classes_args);
        auto gpu = start_gpu(classes);
        std::map<std::string, std::string> files;
        try {
            files = kitti_layout_files(render_stereo_frame(gpu->renderer, document, sensor_options),
                                       sensors_frame);
        } catch (const std::invalid_argument& e) {
            throw Failure{"cannot render the sensors", e.what(), sensors_input};
        }
        try {
            write_files(sensors_out, files);
        } catch (const std::exception& e) {
            throw Failure{"cannot write the sensor files", e.what(), sensors_out};
        }
        return 0;
    }

    if (*grid) {
        if (!grid_labels.empty() && grid_labels.size() != grid_inputs.size()) {
            usage(std::to_string(grid_labels.size()) + " labels for " +
                      std::to_string(grid_inputs.size()) + " inputs",
                  "--labels");
        }
        std::vector<scene_schema::EntityDocument> documents;
        for (const auto& path : grid_inputs) documents.push_back(read_entities(path));
        RenderOptions options = render_options(grid_view, documents.front());
        // One camera for every tile: the first file's intrinsics, one BEV framing all files.
        options.view.intrinsics = documents.front().frame.camera;
        if (options.view.kind == ViewKind::bev) {
            scene_schema::EntityDocument all;
            for (const auto& d : documents) {
                all.entities.insert(all.entities.end(), d.entities.begin(), d.entities.end());
            }
            const ViewSpec fitted = bev_view_fitting(
                all, static_cast<float>(options.width_px) / static_cast<float>(options.height_px));
            options.view.bev_centre_xz = fitted.bev_centre_xz;
            options.view.bev_half_height_m = fitted.bev_half_height_m;
            options.fit_bev = false;
        }
        const auto cloud = read_cloud(grid_view);
        const auto classes = read_classes(grid_view);
        if (grid_labels.empty()) {
            for (const auto& path : grid_inputs) {
                grid_labels.push_back(std::filesystem::path(path).stem().string());
            }
        }
        auto gpu = start_gpu(classes);
        std::vector<ImageRgba8> tiles;
        for (const auto& document : documents) {
            gpu->renderer.load(document, cloud ? &*cloud : nullptr, options);
            if (classes) warn_boxes(gpu->renderer, *classes);
            tiles.push_back(gpu->renderer.render_frame());
        }
        GridFigureOptions figure;
        figure.columns = grid_columns;
        write_output(grid_output, compose_grid(tiles, grid_labels, figure));
        return 0;
    }

    if (input.empty()) usage("an entity file is required", "input");
    if (output.empty() && glb.empty()) usage("an output path is required", "--output/--glb");
    const auto document = read_entities(input);
    RenderOptions options = render_options(view, document);
    if (!(opacity >= 0.0f && opacity <= 1.0f)) usage("must be in 0..1", "--opacity");
    std::optional<ImageRgba8> background_image;
    if (!background.empty()) {
        if (options.view.kind != ViewKind::camera) usage("needs --view camera", "--background");
        try {
            background_image = decode_image(background);
        } catch (const std::exception& e) {
            throw Failure{"cannot read background image", e.what(), "--background"};
        }
        options.keep_alpha = true;
    }
    const auto cloud = read_cloud(view);
    const auto classes = read_classes(view);

    auto gpu = start_gpu(classes);
    gpu->renderer.load(document, cloud ? &*cloud : nullptr, options);
    if (classes) warn_boxes(gpu->renderer, *classes);
    // Everything is built in memory before the first file is written.
    std::vector<unsigned char> glb_bytes;
    if (!glb.empty()) {
        try {
            glb_bytes = export_scene_glb_bytes(gpu->renderer.placed_models());
        } catch (const std::exception& e) {
            throw Failure{"cannot export the scene", e.what(), glb};
        }
    }
    if (!output.empty()) {
        ImageRgba8 image = gpu->renderer.render_frame();
        if (background_image) {
            composite_over(image, resize_nearest(*background_image, image.width, image.height),
                           opacity,
                           options.shading == Shading::lit ? kLitBackground : kSemanticBackground);
        }
        write_output(output, image);
    }
    if (!glb.empty()) {
        try {
            stereoscene::support::write_file_atomic(
                glb, std::string_view(reinterpret_cast<const char*>(glb_bytes.data()),
                                      glb_bytes.size()));
        } catch (const std::exception& e) {
            throw Failure{"cannot write the scene", e.what(), glb};
        }
    }
    return 0;
}

}  // namespace

int main(int argc, char** argv) {
    stereoscene::support::keep_freed_memory();
    using stereoscene::support::error_line;
    try {
        return run(argc, argv);
    } catch (const Failure& f) {
        std::cerr << error_line("scene-render", f.where, f.what + ": " + f.detail) << "\n";
        return f.code;
    } catch (const scene_render::html_command::Failure& f) {
        std::cerr << error_line("scene-render", f.where, f.what + ": " + f.detail) << "\n";
        return f.code;
    } catch (const std::exception& e) {
        std::cerr << error_line("scene-render", "", std::string("rendering failed: ") + e.what())
                  << "\n";
        return 1;
    }
}
