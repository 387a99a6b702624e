#include "html_command.hpp"

#include <filesystem>
#include <iostream>
#include <map>
#include <memory>
#include <optional>

#include "scene_schema/entities.hpp"
#include "scene_schema/json_text.hpp"
#include "scene_schema/sequence.hpp"
#include "scene_viewer/assets/class_table.hpp"
#include "scene_viewer/assets/image_io.hpp"
#include "scene_viewer/assets/scene_export.hpp"
#include "scene_viewer/gfx/null_device.hpp"
#include "scene_viewer/render/scene_renderer.hpp"
#include "scene_viewer/sensors/stereo_sensors.hpp"
#include "scene_viewer/web/viewer_folder.hpp"
#include "stereoscene/support/file_read.hpp"

namespace scene_render::html_command {
namespace {

using namespace scene_viewer;

ViewerLayer read_layer(const std::string& path, const std::string& label) {
    return ViewerLayer{label, read_entities(path)};
}

/// The sequence index an input names (a folder holding sequence.json, or an index file), or
/// nothing for an entity file.
std::optional<std::filesystem::path> drive_index(const std::string& input) {
    std::error_code ec;
    if (input != "-" && std::filesystem::is_directory(input, ec))
        return std::filesystem::path(input) / "sequence.json";
    if (input == "-" || !std::filesystem::is_regular_file(input, ec)) return std::nullopt;
    try {
        const nlohmann::json json =
            scene_schema::parse_json(stereoscene::support::read_text_input(input));
        if (scene_schema::is_sequence_index(json)) return std::filesystem::path(input);
    } catch (const std::exception&) {
        // Not JSON: read_layer reports it as an entity file.
    }
    return std::nullopt;
}

/// Every frame of the drive with its left image (--backgrounds/<entity file stem>.png).
ViewerDrive read_drive(const Options& o, const std::filesystem::path& index_path) {
    scene_schema::SequenceIndex index;
    try {
        index = scene_schema::read_sequence_file(index_path);
    } catch (const std::exception& e) {
        throw Failure{"cannot read the drive", e.what(), index_path.string()};
    }
    if (index.frames.empty())
        throw Failure{"cannot show the drive", "it has no frames", index_path.string()};
    ViewerDrive drive;
    drive.id = index.id;
    drive.fps = o.fps > 0.0 ? o.fps : index.fps.value_or(10.0);
    drive.trail_frames = o.trail;
    for (const scene_schema::SequenceFrame& f : index.frames) {
        ViewerDriveFrame frame;
        frame.index = f.index;
        frame.timestamp_s = f.timestamp_s;
        frame.name = std::filesystem::path(f.file).stem().string();
        const std::filesystem::path file = scene_schema::frame_file(index_path, f);
        frame.document = read_layer(file.string(), frame.name).document;
        if (!frame.timestamp_s) frame.timestamp_s = frame.document.frame.timestamp_s;
        if (!o.backgrounds.empty()) {
            const std::filesystem::path image =
                std::filesystem::path(o.backgrounds) / (frame.name + ".png");
            try {
                const std::vector<unsigned char> bytes =
                    stereoscene::support::read_binary_input(image);
                frame.background_bytes.assign(bytes.begin(), bytes.end());
            } catch (const stereoscene::support::FileError& e) {
                throw Failure{"cannot read background image", e.reason(), image.string()};
            }
            if (web_image_extension(frame.background_bytes).empty())
                throw Failure{"cannot read background image", "neither PNG nor JPEG",
                              image.string()};
        }
        drive.frames.push_back(std::move(frame));
    }
    return drive;
}

/// The first file's models (or boxes) and the ego car, placed as scene-render draws them.
std::vector<unsigned char> scene_glb(const Options& o, const scene_schema::EntityDocument& doc) {
    std::optional<ClassTable> classes;
    if (!o.boxes) {
        const std::filesystem::path path =
            o.classes.empty() ? default_class_table_path() : std::filesystem::path(o.classes);
        try {
            classes = load_class_table(path);
        } catch (const std::exception& e) {
            throw Failure{"cannot read class table", e.what(),
                          o.classes.empty() ? path.string() : "--classes"};
        }
    }
    // The export needs no GL: the null device takes the uploads.
    NullDevice device;
    SceneRenderer renderer(device);
    if (classes) {
        try {
            use_class_models(renderer, *classes);
        } catch (const std::exception& e) {
            throw Failure{"cannot load class model", e.what(), classes->source.string()};
        }
    }
    RenderOptions options;
    options.view = chase_view();  // a view that places the ego car
    options.ego = !o.no_ego;
    options.grid = false;
    renderer.load(doc, nullptr, options);
    try {
        return export_scene_glb_bytes(renderer.placed_models());
    } catch (const std::exception& e) {
        throw Failure{"cannot export the scene", e.what(), o.inputs.front()};
    }
}

}  // namespace

CLI::App* add(CLI::App& app, Options& o) {
    CLI::App* html = app.add_subcommand(
        "html", "write an interactive browser viewer folder (see docs/viewer.md)");
    html->add_option("inputs", o.inputs,
                     "entity files (the scene, then files to compare with it), or one drive "
                     "(sequence index, or a folder with sequence.json)")
        ->required();
    html->add_option("--out", o.out_dir, "output folder")->required();
    html->add_option("--labels", o.labels, "one label per input (default: file names)");
    html->add_option("--cloud", o.cloud, "point cloud (.ply, .pcd, .xyz)");
    html->add_option("--background", o.background, "left image, shown behind the camera view");
    html->add_option("--classes", o.classes,
                     "class table (default: assets/classes/render_classes.json)");
    html->add_flag("--boxes", o.boxes, "draw every entity as a box (no glTF models)");
    html->add_flag("--no-ego", o.no_ego, "no ego car");
    html->add_option("--title", o.title, "page title (default: the first file's name)");
    html->add_option("--point-size", o.point_size_px, "cloud point size in pixels")
        ->capture_default_str();
    html->add_option("--moving-points", o.moving_points,
                     "cloud points drawn while the view moves (a uniform sample; all once it "
                     "stops), 0 = all")
        ->capture_default_str();
    html->add_option("--backgrounds", o.backgrounds,
                     "a drive's left images: folder of <entity file stem>.png");
    html->add_option("--trail", o.trail, "a drive's track trails, frames (0 = none)")
        ->capture_default_str();
    html->add_option("--fps", o.fps, "a drive's frame rate, Hz (default: the index's, else 10)");
    return html;
}

namespace {

/// The page's settings: title, point size, moving points.
ViewerOptions viewer_options(const Options& o) {
    ViewerOptions viewer;
    viewer.title =
        o.title.empty() ? std::filesystem::path(o.inputs.front()).stem().string() : o.title;
    viewer.point_size_px = o.point_size_px;
    viewer.moving_points = o.moving_points;
    try {
        viewer.validate();
    } catch (const std::invalid_argument& e) {
        throw Failure{"bad usage", e.what(), "--point-size/--moving-points", 2};
    }
    return viewer;
}

/// The page, its script and three.js, from --web-dir or the installed assets.
ViewerAssets viewer_assets(const Options& o) {
    const std::filesystem::path web_dir =
        o.web_dir.empty() ? default_viewer_assets_dir() : std::filesystem::path(o.web_dir);
    ViewerAssets assets;
    try {
        assets = load_viewer_assets(web_dir);
    } catch (const std::exception& e) {
        throw Failure{"cannot read the viewer's files (scripts/install-deps.sh installs three.js)",
                      e.what(), web_dir.string()};
    }
    return assets;
}

/// --cloud (kept in `cloud`, which the scene points to) and --background, into the scene.
void add_cloud_and_background(const Options& o, ViewerScene& scene,
                              std::optional<PointCloud>& cloud) {
    if (!o.cloud.empty()) {
        try {
            cloud = read_point_cloud(o.cloud);
        } catch (const std::exception& e) {
            throw Failure{"cannot read point cloud", e.what(), "--cloud"};
        }
        scene.cloud = &*cloud;
    }
    if (!o.background.empty()) {
        try {
            const std::vector<unsigned char> png = encode_png(decode_image(o.background), 6);
            scene.background_bytes.assign(png.begin(), png.end());
        } catch (const std::exception& e) {
            throw Failure{"cannot read background image", e.what(), "--background"};
        }
        scene.background_name = "left.png";
    }
}

}  // namespace

int run(const Options& o) {
    if (!o.labels.empty() && o.labels.size() != o.inputs.size()) {
        throw Failure{"bad usage",
                      std::to_string(o.labels.size()) + " labels for " +
                          std::to_string(o.inputs.size()) + " inputs",
                      "--labels", 2};
    }
    check_output_folder(o.out_dir, "cannot write the viewer");
    ViewerOptions viewer = viewer_options(o);
    const ViewerAssets assets = viewer_assets(o);
    if (o.trail < 0 || o.trail > 100000) usage("must be in 0..100000", "--trail");
    if (!(o.fps >= 0.0 && o.fps <= 1000.0)) usage("must be in (0, 1000]", "--fps");
    const std::optional<std::filesystem::path> index_path = drive_index(o.inputs.front());
    std::optional<ViewerDrive> drive;
    if (index_path) {
        if (o.inputs.size() > 1) usage("a drive is shown alone", o.inputs[1]);
        if (!o.cloud.empty()) usage("not with a drive", "--cloud");
        if (!o.background.empty()) usage("not with a drive (use --backgrounds)", "--background");
        drive = read_drive(o, *index_path);
        if (o.title.empty()) viewer.title = drive->id;
    } else if (!o.backgrounds.empty()) {
        usage("needs a drive (a sequence index) as input", "--backgrounds");
    }
    ViewerScene scene;
    if (drive) {
        scene.layers.push_back(ViewerLayer{drive->id, drive->frames.front().document});
        scene.drive = &*drive;
    }
    for (std::size_t i = 0; !drive && i < o.inputs.size(); ++i) {
        scene.layers.push_back(read_layer(
            o.inputs[i],
            o.labels.empty() ? std::filesystem::path(o.inputs[i]).stem().string() : o.labels[i]));
    }
    std::optional<PointCloud> cloud;
    add_cloud_and_background(o, scene, cloud);
    scene.scene_glb = scene_glb(o, scene.layers.front().document);
    if (drive) drive->models_glb = scene_glb(o, class_template_document(drive_classes(*drive)));
    std::map<std::string, std::string> files;
    try {
        files = viewer_files(scene, assets, viewer);
    } catch (const std::exception& e) {
        throw Failure{"cannot build the viewer", e.what(), o.out_dir};
    }
    try {
        write_files(o.out_dir, files);
    } catch (const std::exception& e) {
        throw Failure{"cannot write the viewer", e.what(), o.out_dir};
    }
    return 0;
}

}  // namespace scene_render::html_command
