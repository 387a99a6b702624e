#include "scene_viewer/web/viewer_drive.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <stdexcept>

#include "scene_viewer/assets/palette.hpp"
#include "scene_viewer/ecs/coordinates.hpp"
#include "scene_viewer/views/trails.hpp"
#include "scene_viewer/web/viewer_folder.hpp"
#include "stereoscene/support/angles.hpp"

using stereoscene::support::kPi;

namespace scene_viewer {
namespace {

/// "frames/000042" for the frame at position 42 of the drive.
std::string frame_stem(std::size_t position) {
    char text[32];
    std::snprintf(text, sizeof text, "frames/%06zu", position);
    return text;
}

/// The frame's left image in the folder, or null.
nlohmann::json image_file(const ViewerDriveFrame& frame, std::size_t position) {
    if (frame.background_bytes.empty()) return nullptr;
    const std::string ext = web_image_extension(frame.background_bytes);
    if (ext.empty())
        throw std::invalid_argument("the left image of frame " + frame.name +
                                    " is neither PNG nor JPEG");
    return frame_stem(position) + ext;
}

/// The classic script of one frame: hands its entities to the page (file:// pages may not
/// fetch()).
std::string frame_script(const ViewerDriveFrame& frame, std::size_t position) {
    const nlohmann::json entities = scene_schema::to_json(frame.document).at("entities");
    const nlohmann::json payload = {{"position", position}, {"entities", entities}};
    return "window.SceneViewerFrames.add(" +
           payload.dump(-1, ' ', false, nlohmann::json::error_handler_t::replace) + ");\n";
}

}  // namespace

std::string web_image_extension(const std::string& bytes) {
    static const std::string kPng = "\x89PNG\r\n\x1a\n";
    if (bytes.compare(0, kPng.size(), kPng) == 0) return ".png";
    if (bytes.size() >= 3 && static_cast<unsigned char>(bytes[0]) == 0xff &&
        static_cast<unsigned char>(bytes[1]) == 0xd8 &&
        static_cast<unsigned char>(bytes[2]) == 0xff)
        return ".jpg";
    return "";
}

scene_schema::EntityDocument class_template_document(const std::map<std::string, int>& classes) {
    scene_schema::EntityDocument document;
    for (const auto& [name, id] : classes) {
        if (is_ground_class(id, name)) continue;
        scene_schema::Entity e;
        e.id = kClassTemplatePrefix + name;
        e.class_name = name;
        e.class_id = id;
        e.theta = 0.5 * kPi;  // the page's placement rotates by pi/2 - theta: none
        e.W = e.H = e.L = 1.0;
        document.entities.push_back(std::move(e));
    }
    return document;
}

std::map<std::string, int> drive_classes(const ViewerDrive& drive) {
    std::map<std::string, int> classes;
    for (const ViewerDriveFrame& f : drive.frames) {
        for (const auto& e : f.document.entities) classes.emplace(e.class_name, e.class_id);
    }
    return classes;
}

nlohmann::json drive_json(const ViewerDrive& drive) {
    nlohmann::json frames = nlohmann::json::array();
    std::map<std::int64_t, nlohmann::json> tracks;
    double min_x = -2.0, max_x = 2.0, min_z = -4.0, max_z = 4.0;  // bev_view_fitting's floor
    // With a pose on every frame, trails lie in the drive's world (the first frame's camera)
    // and each frame says where its camera is; the camera's own path is a track too.
    const bool world = std::all_of(drive.frames.begin(), drive.frames.end(),
                                   [](const auto& f) { return f.document.frame.pose.has_value(); });
    const auto add_point = [&](std::int64_t id, const std::string& cls, std::size_t i,
                               const glm::dvec4& p) {
        nlohmann::json& track = tracks[id];
        if (track.is_null()) track = {{"class", cls}, {"points", nlohmann::json::array()}};
        track["points"].push_back({i, p.x, p.y, p.z});
    };
    for (std::size_t i = 0; i < drive.frames.size(); ++i) {
        const ViewerDriveFrame& f = drive.frames[i];
        const double t = f.timestamp_s ? *f.timestamp_s : static_cast<double>(f.index) / drive.fps;
        nlohmann::json frame = {{"index", f.index},
                                {"time", t},
                                {"name", f.name},
                                {"script", frame_stem(i) + ".js"},
                                {"image", image_file(f, i)},
                                {"entities", f.document.entities.size()}};
        const glm::dmat4 world_from_camera =
            world ? kitti_pose_matrix(*f.document.frame.pose) : glm::dmat4(1.0);
        if (world) {
            // Column-major 4x4 (three.js Matrix4.fromArray): the world seen from this camera.
            const glm::dmat4 camera_from_world = glm::inverse(world_from_camera);
            nlohmann::json m = nlohmann::json::array();
            for (int c = 0; c < 4; ++c) {
                for (int r = 0; r < 4; ++r) m.push_back(camera_from_world[c][r]);
            }
            frame["camera_from_world"] = std::move(m);
            add_point(kEgoTrack, kEgoClassName, i,
                      world_from_camera * glm::dvec4(0.0, kEgoGroundBelow_m, 0.0, 1.0));
        }
        frames.push_back(std::move(frame));
        for (const auto& e : f.document.entities) {
            const double r = 0.5 * std::hypot(e.W, e.L);
            min_x = std::min(min_x, e.x - r);
            max_x = std::max(max_x, e.x + r);
            min_z = std::min(min_z, e.z - r);
            max_z = std::max(max_z, e.z + r);
            if (!e.track_id) continue;
            // Ground contact: the box's bottom (KITTI y grows downwards).
            add_point(*e.track_id, e.class_name, i,
                      world_from_camera * glm::dvec4(e.x, e.y + 0.5 * e.H, e.z, 1.0));
        }
    }
    nlohmann::json track_list = nlohmann::json::array();
    for (auto& [id, track] : tracks) {
        track["id"] = id;
        track_list.push_back(std::move(track));
    }
    return {{"id", drive.id},
            {"fps", drive.fps},
            {"trail_frames", drive.trail_frames},
            {"world", world},
            {"frames", frames},
            {"tracks", track_list},
            {"extent", {min_x, max_x, min_z, max_z}},
            {"models_file", "models.glb"}};
}

void add_drive_files(const ViewerDrive& drive, std::map<std::string, std::string>& files) {
    if (drive.frames.empty()) throw std::invalid_argument("the drive has no frames");
    for (std::size_t i = 0; i < drive.frames.size(); ++i) {
        const ViewerDriveFrame& f = drive.frames[i];
        files[frame_stem(i) + ".js"] = frame_script(f, i);
        const nlohmann::json image = image_file(f, i);
        if (!image.is_null()) files[image.get<std::string>()] = f.background_bytes;
    }
    std::string& models = files["models.glb"];
    models.assign(drive.models_glb.begin(), drive.models_glb.end());
    files["data/models-glb.js"] =
        "(window.SCENE_VIEWER_BLOBS = window.SCENE_VIEWER_BLOBS || {})[\"models.glb\"] = \"" +
        base64_encode(reinterpret_cast<const unsigned char*>(models.data()), models.size()) +
        "\";\n";
}

}  // namespace scene_viewer
