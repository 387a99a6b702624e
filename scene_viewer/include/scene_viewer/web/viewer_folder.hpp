#pragma once

/// The browser viewer: a self-contained folder (index.html, the scene as .glb, the cloud as a
/// glTF POINTS .glb, the left image, three.js) that opens from disk or any static web server.
/// Data reach the page through classic <script> files (file:// pages may not fetch() nor import
/// modules in Chromium), so nothing is requested outside the folder. See docs/viewer.md.

#include <filesystem>
#include <map>
#include <string>
#include <vector>

#include "scene_schema/entities.hpp"
#include "scene_viewer/assets/point_cloud.hpp"
#include "scene_viewer/web/viewer_drive.hpp"

namespace scene_viewer {

/// One entity file shown by the viewer.
struct ViewerLayer {
    std::string label;                      ///< name in the page (e.g. the file stem)
    scene_schema::EntityDocument document;  ///< the entities
};

/// What the page shows. The first layer is the scene (drawn with its models from scene_glb);
/// further layers are compared with it (boxes in per-file colours). With a drive, the first
/// layer is the drive's first frame and the page shows the frames on a timeline.
struct ViewerScene {
    std::vector<ViewerLayer> layers;       ///< at least one
    std::vector<unsigned char> scene_glb;  ///< export_scene_glb_bytes() of the first layer
    const PointCloud* cloud = nullptr;     ///< optional point cloud (KITTI frame), borrowed
    std::string background_name;           ///< file name of the left image in the folder, or ""
    std::string background_bytes;          ///< its bytes, copied as they are
    const ViewerDrive* drive = nullptr;    ///< a drive (one layer, no cloud), borrowed, or null
};

/// Page settings.
struct ViewerOptions {
    std::string title = "scene";  ///< page title
    float point_size_px = 2.0f;   ///< cloud point size, pixels, > 0
    int moving_points = 30000;    ///< cloud points drawn while the view moves, 0 = all
    /// Throws std::invalid_argument naming the bad field.
    void validate() const;
};

/// The page's own scripts, in the order index.html loads them (helpers first, viewer.js last).
inline constexpr const char* kViewerScripts[] = {"viewer_util.js", "viewer_models.js",
                                                 "viewer_panel.js", "viewer_drive.js", "viewer.js"};

/// The viewer's static files: three.js (bundled with its orbit controls and glTF loader), the
/// HTML template (placeholders {{TITLE}} and {{DATA_SCRIPTS}}), the style sheet and the page's
/// scripts (kViewerScripts: file name -> text).
struct ViewerAssets {
    std::string three_js;
    std::string index_html;
    std::string viewer_css;
    std::map<std::string, std::string> scripts;
};

/// Reads the viewer's static files from `dir`; throws std::runtime_error naming a missing file.
ViewerAssets load_viewer_assets(const std::filesystem::path& dir);

/// The viewer's static files: share/stereoscene/web of an install (beside the executable's
/// folder), else where the build put them (scene_viewer/web of the build tree).
std::filesystem::path default_viewer_assets_dir();

/// The point cloud as binary glTF: one POINTS mesh per class (node "cloud_class_<id>", or
/// "cloud" without classes), positions in the glTF frame (+Y up, metres), COLOR_0 as
/// normalised linear bytes when the cloud has colours, else the class colour as material.
/// Each class's points are in a fixed pseudo-random order, so any prefix is a uniform sample
/// (the viewer draws a prefix while the view moves).
std::vector<unsigned char> point_cloud_glb_bytes(const PointCloud& cloud);

/// Standard base64 (RFC 4648, with padding).
std::string base64_encode(const unsigned char* data, std::size_t size);

/// Every file of the viewer folder, relative path -> bytes: index.html, viewer.js, viewer.css,
/// three.min.js, scene.glb, cloud.glb (with a cloud), the background image (with one) and
/// data/*.js (page data and the .glb files as base64 for file:// pages), and with a drive its
/// files (add_drive_files). Throws std::invalid_argument for no layers, bad options, or a drive
/// beside a cloud or compared files.
std::map<std::string, std::string> viewer_files(const ViewerScene& scene,
                                                const ViewerAssets& assets,
                                                const ViewerOptions& options);

}  // namespace scene_viewer
