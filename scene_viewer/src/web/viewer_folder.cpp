#include "scene_viewer/web/viewer_folder.hpp"

#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <set>
#include <sstream>
#include <stdexcept>

#include <nlohmann/json.hpp>

#include "scene_viewer/assets/palette.hpp"
#include "scene_viewer/ecs/coordinates.hpp"
#include "scene_viewer/render/scene_renderer.hpp"
#include "scene_viewer/views/views.hpp"
#include "stereoscene/support/angles.hpp"
#include "stereoscene/support/asset_dir.hpp"
#include "stereoscene/support/file_read.hpp"

using stereoscene::support::kPi;

namespace scene_viewer {
namespace {

/// Colours of compared files, in order (distinct on the light background and from each other).
constexpr const char* kLayerColours[] = {"#e6194b", "#1f77b4", "#2ca02c", "#ff7f0e",
                                         "#9467bd", "#17becf", "#8c564b", "#bcbd22"};

std::string hex_colour(const Rgb8& c) {
    char text[8];
    std::snprintf(text, sizeof text, "#%02x%02x%02x", c[0], c[1], c[2]);
    return text;
}

std::string read_text(const std::filesystem::path& path) {
    return stereoscene::support::read_text_input(path);
}

nlohmann::json vec3_json(const glm::vec3& v) { return nlohmann::json::array({v.x, v.y, v.z}); }

/// The frame's camera, or the 60 degree camera scene-render uses for a file without one.
scene_schema::CameraIntrinsics camera_of(const scene_schema::EntityDocument& document) {
    if (document.frame.camera) return *document.frame.camera;
    const RenderOptions defaults;
    scene_schema::CameraIntrinsics k;
    k.width_px = defaults.width_px;
    k.height_px = defaults.height_px;
    k.fy_px = 0.5 * k.height_px /
              std::tan(0.5 * static_cast<double>(defaults.view.fov_y_deg) * kPi / 180.0);
    k.fx_px = k.fy_px;
    k.cx_px = 0.5 * k.width_px;
    k.cy_px = 0.5 * k.height_px;
    return k;
}

/// The views of views.cpp in the glTF/OpenGL frame the page works in.
nlohmann::json views_json(const scene_schema::EntityDocument& document) {
    const scene_schema::CameraIntrinsics k = camera_of(document);
    const ViewSpec defaults;
    const ViewSpec chase = chase_view();
    return {{"camera",
             {{"width", k.width_px},
              {"height", k.height_px},
              {"fx", k.fx_px},
              {"fy", k.fy_px},
              {"cx", k.cx_px},
              {"cy", k.cy_px},
              {"near", defaults.near_m},
              {"far", defaults.far_m}}},
            {"chase",
             {{"eye", vec3_json(kitti_to_gl(chase.eye_kitti))},
              {"target", vec3_json(kitti_to_gl(chase.target_kitti))},
              {"fov", chase.fov_y_deg}}},
            {"bev", {{"height_m", 200.0}, {"margin", 1.05}}}};
}

/// Name, id, colour and ground flag of every class of the layers and the cloud.
nlohmann::json classes_json(const ViewerScene& scene) {
    std::map<std::string, nlohmann::json> classes;
    for (const ViewerLayer& layer : scene.layers) {
        for (const auto& e : layer.document.entities) {
            if (classes.count(e.class_name)) continue;
            classes[e.class_name] = {{"name", e.class_name},
                                     {"id", e.class_id},
                                     {"colour", hex_colour(class_colour(e.class_id, e.class_name))},
                                     {"ground", is_ground_class(e.class_id, e.class_name)}};
        }
    }
    if (scene.drive != nullptr) {
        for (const auto& [name, id] : drive_classes(*scene.drive)) {
            if (classes.count(name)) continue;
            classes[name] = {{"name", name},
                             {"id", id},
                             {"colour", hex_colour(class_colour(id, name))},
                             {"ground", is_ground_class(id, name)}};
        }
    }
    if (scene.cloud != nullptr) {
        for (int id : std::set<int>(scene.cloud->class_ids.begin(), scene.cloud->class_ids.end())) {
            const auto entry = cityscapes_by_id(id);
            const std::string name = entry ? entry->name : "class " + std::to_string(id);
            if (classes.count(name)) continue;
            classes[name] = {{"name", name},
                             {"id", id},
                             {"colour", hex_colour(class_colour(id, name))},
                             {"ground", is_ground_class(id, name)}};
        }
    }
    nlohmann::json out = nlohmann::json::array();
    for (auto& [name, c] : classes) out.push_back(std::move(c));
    return out;
}

/// The page data: views, light, classes, layers with their entities, cloud summary.
std::string data_script(const ViewerScene& scene, const ViewerOptions& options) {
    const FrameSetup light;
    nlohmann::json layers = nlohmann::json::array();
    for (std::size_t i = 0; i < scene.layers.size(); ++i) {
        const nlohmann::json document = scene_schema::to_json(scene.layers[i].document);
        layers.push_back({{"label", scene.layers[i].label},
                          {"colour", kLayerColours[i % std::size(kLayerColours)]},
                          {"entities", document.at("entities")}});
    }
    nlohmann::json cloud = nullptr;
    if (scene.cloud != nullptr) {
        cloud = {{"points", scene.cloud->size()},
                 {"coloured", !scene.cloud->colours.empty()},
                 {"file", "cloud.glb"}};
    }
    const nlohmann::json data = {
        {"title", options.title},
        {"views", views_json(scene.layers.front().document)},
        {"light", {{"direction", vec3_json(light.light_direction)}, {"ambient", light.ambient}}},
        {"background_colour", hex_colour(kLitBackground)},
        {"ego_colour", hex_colour(kLitEgoColour)},
        {"background_image", scene.background_name.empty() ? nlohmann::json(nullptr)
                                                           : nlohmann::json(scene.background_name)},
        {"classes", classes_json(scene)},
        {"layers", layers},
        {"scene_file", "scene.glb"},
        {"cloud", cloud},
        {"point_size", options.point_size_px},
        {"moving_points", options.moving_points},
        {"drive", scene.drive ? drive_json(*scene.drive) : nlohmann::json(nullptr)}};
    return "window.SCENE_VIEWER_DATA = " +
           data.dump(-1, ' ', false, nlohmann::json::error_handler_t::replace) + ";\n";
}

/// A classic script that hands a binary file to the page as base64.
std::string blob_script(const std::string& name, const std::string& bytes) {
    return "(window.SCENE_VIEWER_BLOBS = window.SCENE_VIEWER_BLOBS || {})[\"" + name + "\"] = \"" +
           base64_encode(reinterpret_cast<const unsigned char*>(bytes.data()), bytes.size()) +
           "\";\n";
}

std::string replace_all(std::string text, const std::string& from, const std::string& to) {
    for (std::size_t at = text.find(from); at != std::string::npos;
         at = text.find(from, at + to.size())) {
        text.replace(at, from.size(), to);
    }
    return text;
}

std::string html_escape(const std::string& text) {
    std::string out;
    for (char c : text) {
        switch (c) {
            case '&':
                out += "&amp;";
                break;
            case '<':
                out += "&lt;";
                break;
            case '>':
                out += "&gt;";
                break;
            case '"':
                out += "&quot;";
                break;
            default:
                out += c;
        }
    }
    return out;
}

}  // namespace

void ViewerOptions::validate() const {
    if (!(point_size_px > 0.0f && point_size_px <= 64.0f))
        throw std::invalid_argument("point_size_px must be in (0, 64] pixels");
    if (moving_points < 0) throw std::invalid_argument("moving_points must be >= 0");
}

ViewerAssets load_viewer_assets(const std::filesystem::path& dir) {
    ViewerAssets a;
    a.three_js = read_text(dir / "three.min.js");
    a.viewer_css = read_text(dir / "viewer.css");
    for (const char* name : kViewerScripts) a.scripts[name] = read_text(dir / name);
    a.index_html = read_text(dir / "index.html");
    return a;
}

namespace {

/// The viewer's files in an install, relative to the folder holding the executable.
constexpr const char* kInstalledViewerFromBin = "../share/stereoscene/web";

}  // namespace

std::filesystem::path default_viewer_assets_dir() {
    std::error_code ec;
    const std::filesystem::path bin = stereoscene::support::executable_dir();
    const std::filesystem::path installed = (bin / kInstalledViewerFromBin).lexically_normal();
    if (!bin.empty() && std::filesystem::is_directory(installed, ec)) return installed;
    return SCENE_VIEWER_WEB_DIR;
}

std::string base64_encode(const unsigned char* data, std::size_t size) {
    static constexpr char kDigits[] =
        "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
    std::string out;
    out.reserve((size + 2) / 3 * 4);
    std::size_t i = 0;
    for (; i + 2 < size; i += 3) {
        const unsigned v = (data[i] << 16) | (data[i + 1] << 8) | data[i + 2];
        out += kDigits[(v >> 18) & 63];
        out += kDigits[(v >> 12) & 63];
        out += kDigits[(v >> 6) & 63];
        out += kDigits[v & 63];
    }
    if (i < size) {
        const unsigned v = (data[i] << 16) | (i + 1 < size ? data[i + 1] << 8 : 0);
        out += kDigits[(v >> 18) & 63];
        out += kDigits[(v >> 12) & 63];
        out += i + 1 < size ? kDigits[(v >> 6) & 63] : '=';
        out += '=';
    }
    return out;
}

std::map<std::string, std::string> viewer_files(const ViewerScene& scene,
                                                const ViewerAssets& assets,
                                                const ViewerOptions& options) {
    options.validate();
    if (scene.layers.empty()) throw std::invalid_argument("viewer_files: no entity file");
    if (scene.drive != nullptr && (scene.layers.size() > 1 || scene.cloud != nullptr))
        throw std::invalid_argument(
            "viewer_files: a drive is shown alone (no cloud, no compared file)");
    if (scene.background_name.find_first_of("/\\\"<>&") != std::string::npos)
        throw std::invalid_argument("viewer_files: bad background file name");
    std::map<std::string, std::string> files;
    files["three.min.js"] = assets.three_js;
    files["viewer.css"] = assets.viewer_css;
    for (const auto& [name, text] : assets.scripts) files[name] = text;
    files["scene.glb"].assign(scene.scene_glb.begin(), scene.scene_glb.end());
    files["data/scene-data.js"] = data_script(scene, options);
    files["data/scene-glb.js"] = blob_script("scene.glb", files["scene.glb"]);
    std::string scripts =
        "<script src=\"data/scene-data.js\"></script>\n"
        "<script src=\"data/scene-glb.js\"></script>\n";
    if (scene.cloud != nullptr) {
        const std::vector<unsigned char> cloud = point_cloud_glb_bytes(*scene.cloud);
        files["cloud.glb"].assign(cloud.begin(), cloud.end());
        files["data/cloud-glb.js"] = blob_script("cloud.glb", files["cloud.glb"]);
        // Deferred: the page draws the scene first and adds the cloud once this has run.
        scripts += "<script id=\"cloud-data\" src=\"data/cloud-glb.js\" defer></script>\n";
    }
    if (scene.drive != nullptr) {
        add_drive_files(*scene.drive, files);
        scripts += "<script src=\"data/models-glb.js\"></script>\n";
    }
    if (!scene.background_name.empty()) files[scene.background_name] = scene.background_bytes;
    std::string html = replace_all(assets.index_html, "{{TITLE}}", html_escape(options.title));
    files["index.html"] = replace_all(html, "{{DATA_SCRIPTS}}", scripts);
    return files;
}

}  // namespace scene_viewer
