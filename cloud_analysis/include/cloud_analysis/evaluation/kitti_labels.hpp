#pragma once

/// KITTI object label_2 files (devkit_object readme: one object per line, "type truncated
/// occluded alpha x1 y1 x2 y2 h w l x y z rotation_y [score]", camera 2 rectified frame, y is
/// the BOTTOM of the box) read as entities and written from entities, so KITTI's own tools can
/// score our output.

#include <filesystem>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include <scene_schema/entities.hpp>

#include "cloud_analysis/stereo/calibration.hpp"

namespace cloud_analysis {

/// Where the entities' camera sits in KITTI's label frame. label_2 locations are in rectified
/// camera 0; our entities are in the rectified left camera of the pair (camera 2 on KITTI), whose
/// projection is P2 = K [I | t]: a point X0 of the label frame is X0 + t in the left camera.
/// t = K^-1 P2[:, 3] comes from the calibration (Calibration::reference_offset_m); on KITTI it is
/// about (0.06, 0, 0) m. Zero when the entities' camera is the label frame.
struct LabelFrame {
    double tx_m = 0.0;  ///< t, metres
    double ty_m = 0.0;
    double tz_m = 0.0;
};

/// The label frame of a calibration (its reference_offset_m).
LabelFrame label_frame_of(const Calibration& calibration);

/// The label frame an entity file records (source.calibration.reference_offset_m, written by
/// cloud-analysis), or nothing when the file does not say.
std::optional<LabelFrame> label_frame_of(const scene_schema::EntityDocument& document);

/// One label_2 line.
struct KittiLabel {
    std::string type;        ///< Car, Van, Truck, Pedestrian, ..., DontCare
    double truncated = 0.0;  ///< 0 (inside the image) .. 1 (leaving it)
    int occluded = 0;        ///< 0 visible, 1 partly, 2 largely occluded, 3 unknown
    double alpha = -10.0;    ///< observation angle, radians, [-pi, pi]
    double bbox[4] = {-1.0, -1.0, -1.0, -1.0};  ///< 2D box left, top, right, bottom, px
    double h = 0.0;                             ///< height, metres (our H)
    double w = 0.0;                             ///< width, metres (our W)
    double l = 0.0;                             ///< length, metres (our L)
    double x = 0.0;                             ///< bottom centre x, metres, camera frame
    double y = 0.0;                             ///< bottom centre y (the box BOTTOM), metres
    double z = 0.0;                             ///< bottom centre z, metres
    double rotation_y = 0.0;                    ///< yaw about +y, radians (our theta)
    std::optional<double> score;                ///< detection score (result files only)
};

/// Parses label_2 text (15 or 16 columns a line, blank lines skipped); throws
/// std::runtime_error "cannot read KITTI labels: line N: <rule> (<origin>)".
std::vector<KittiLabel> parse_kitti_labels(std::string_view text, const std::string& origin);

/// Reads a label_2 file; throws std::runtime_error naming the file.
std::vector<KittiLabel> load_kitti_labels(const std::filesystem::path& path);

/// Our class of a KITTI type: Car/Van -> car (26), Truck -> truck (27), Pedestrian and
/// Person_sitting -> person (24), Cyclist -> rider (25), Tram -> train (31); DontCare, Misc
/// and unknown types give nothing (ignored). Cityscapes counts vans as cars.
std::optional<std::pair<std::string, int>> class_of_kitti_type(std::string_view type);

/// KITTI type of our class: car Car, truck Truck, person Pedestrian, rider Cyclist, train
/// Tram, bus/motorcycle/bicycle/caravan/trailer Misc; stuff classes give nothing (not
/// exported).
std::optional<std::string> kitti_type_of_class(std::string_view class_name);

/// Entities of the labels that map to a class (ids "<class>-<line>", centre y = y - h / 2,
/// method "kitti_label_2", confidence = score or 1, `subclass` "car" or "van" for Car and Van),
/// moved from the label frame into the entities' camera (x + t).
std::vector<scene_schema::Entity> entities_from_kitti_labels(const std::vector<KittiLabel>& labels,
                                                             const LabelFrame& frame = {});

/// Label of an entity: type from its class (a car whose `subclass` is "van" is a Van), the
/// location moved into the label frame (x - t), y bottom = y + H / 2,
/// alpha = theta - atan2(x, z) of the label frame's x and z wrapped to [-pi, pi], score =
/// confidence. With the entities' camera, the 2D box is the bounding box of the eight projected
/// corners clipped to the image (-1s when the box is not in front of the camera or off the
/// image): the same as KITTI's projection with P2 of the label's location. Without one, -1s.
KittiLabel kitti_label_from_entity(const scene_schema::Entity& entity,
                                   const scene_schema::CameraIntrinsics* camera,
                                   const LabelFrame& frame = {});

/// label_2 text of labels (16 columns when a label has a score), 2 decimals like KITTI's.
std::string format_kitti_labels(const std::vector<KittiLabel>& labels);

}  // namespace cloud_analysis
