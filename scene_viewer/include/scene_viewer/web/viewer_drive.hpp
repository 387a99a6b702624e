#pragma once

/// A drive in the browser viewer: the sequence's frames as one small classic script each
/// (frames/NNNNNN.js, loaded by the page only when shown), the left images beside them, the
/// track trails and the drive's extent in the page data, and the class models as templates
/// (models.glb: one node per class, the model fitted to the unit box) that the page places for
/// every entity of every frame. See docs/viewer.md.

#include <cstdint>
#include <map>
#include <optional>
#include <set>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "scene_schema/entities.hpp"

namespace scene_viewer {

/// One frame of a drive.
struct ViewerDriveFrame {
    std::int64_t index = 0;             ///< frame number in the drive
    std::optional<double> timestamp_s;  ///< capture time, seconds
    std::string name;                   ///< the entity file's stem (names its left image)
    scene_schema::EntityDocument document;
    std::string background_bytes;  ///< the left image (PNG or JPEG bytes), or empty
};

/// A drive: its frames in capture order and the class models the page places.
struct ViewerDrive {
    std::string id;                         ///< the drive's id
    double fps = 10.0;                      ///< frame rate for frames without timestamps, Hz
    int trail_frames = 20;                  ///< track trail length in frames, 0 = no trails
    std::vector<ViewerDriveFrame> frames;   ///< at least one
    std::vector<unsigned char> models_glb;  ///< class_template_document() exported as .glb
};

/// Prefix of a template node's name: "class:car" holds the car model fitted to the unit box.
inline constexpr const char* kClassTemplatePrefix = "class:";

/// One entity per class drawn with a model (`classes`: name -> class id; ground classes are
/// left out, the page draws them as patches): centre at the origin, W = H = L = 1 and
/// theta = pi/2, so its placed model is the class model fitted to the unit box, in the page's
/// frame without rotation. Entity ids are kClassTemplatePrefix + class name.
scene_schema::EntityDocument class_template_document(const std::map<std::string, int>& classes);

/// ".png" or ".jpg" from the image's first bytes (what browsers show), "" for anything else.
std::string web_image_extension(const std::string& bytes);

/// Name -> class id of every entity in the drive's frames.
std::map<std::string, int> drive_classes(const ViewerDrive& drive);

/// The drive's part of the page data: id, fps, trail length, frames (index, time, script,
/// image), each track's positions per frame (ground plane, KITTI x and z) and the extent of
/// every footprint (for the BEV framing).
nlohmann::json drive_json(const ViewerDrive& drive);

/// Adds the drive's files (frames/NNNNNN.js, frames/NNNNNN.png or .jpg, models.glb,
/// data/models-glb.js) to `files`. Throws std::invalid_argument for a drive without frames or
/// a left image that is neither PNG nor JPEG.
void add_drive_files(const ViewerDrive& drive, std::map<std::string, std::string>& files);

}  // namespace scene_viewer
