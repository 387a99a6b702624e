#pragma once

/// Scoring entities against 2D boxes drawn on the image: what a person sees, for real frames
/// that have no 3D ground truth. Each entity's 3D box is projected with its camera and matched
/// to the labelled boxes by image overlap. See docs/evaluation.md "2D labels" and
/// docs/format.md "2D labels" for the file.

#include <cstddef>
#include <filesystem>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include <Eigen/Core>
#include <scene_schema/entities.hpp>

#include "cloud_analysis/evaluation/kitti_labels.hpp"

namespace cloud_analysis {

/// What a person labels in 2D: vehicles (cars, vans, trucks, buses, trams), people on foot
/// and cyclists (a rider with a bicycle or motorcycle).
enum class Category2d { vehicle = 0, person = 1, cyclist = 2 };
inline constexpr int kCategory2dCount = 3;

/// "vehicle", "person" or "cyclist".
std::string_view category_name(Category2d category);

/// Category of a labelled type (case-insensitive): car, van, truck, bus, tram, train ->
/// vehicle; person, pedestrian, person_sitting -> person; cyclist, rider, bicycle, motorcycle
/// -> cyclist; anything else nothing.
std::optional<Category2d> category_of_type(std::string_view type);

/// Category of an entity class: car, truck, bus, train, caravan, trailer -> vehicle; person ->
/// person; rider, bicycle, motorcycle -> cyclist; other classes nothing (not scored).
std::optional<Category2d> category_of_class(std::string_view class_name);

/// One labelled object. Boxes are (u0, v0, u1, v1) in pixel-edge coordinates (pixel (u, v)
/// covers [u, u + 1) x [v, v + 1)), around the part of the object that is seen.
struct Label2d {
    std::string type;  ///< as labelled: car, van, person, ...
    Category2d category = Category2d::vehicle;
    Eigen::Vector4d box_px = Eigen::Vector4d::Zero();
    int occluded = 0;        ///< 0 fully seen, 1 partly hidden, 2 largely hidden, 3 unknown
    double truncated = 0.0;  ///< share of the object outside the image, [0, 1]
    std::string track;       ///< the same object across frames (optional)
};

/// The labels of one image.
struct FrameLabels2d {
    std::string frame;                       ///< frame id (the image's file stem)
    std::vector<Label2d> objects;            ///< labelled objects
    std::vector<Eigen::Vector4d> dont_care;  ///< regions nobody could label (too far, unclear)
};

/// A labels file: one or more frames.
struct Labels2d {
    std::string origin;  ///< the file read
    int width_px = 0;    ///< image size the boxes refer to (0 = not said)
    int height_px = 0;
    std::vector<FrameLabels2d> frames;  ///< in file order, ids unique
    /// The frame with this id, or nullptr.
    const FrameLabels2d* find(std::string_view frame) const;
};

/// Parses the project's JSON labels (docs/format.md "2D labels"); throws std::runtime_error
/// "cannot read 2D labels: <rule> (<origin>)".
Labels2d parse_labels_2d(std::string_view text, const std::string& origin);

/// The 2D boxes of KITTI label_2 lines as one frame: types with a category are objects,
/// DontCare and Misc are don't-care regions, other types are left out.
FrameLabels2d labels_2d_from_kitti(const std::vector<KittiLabel>& labels, std::string frame);

/// Reads a labels file: KITTI label_2 text when it ends in .txt (one frame, its id the file
/// stem), the project's JSON otherwise. Throws std::runtime_error naming the file.
Labels2d load_labels_2d(const std::filesystem::path& path);

/// The matching rule and which labels are owed.
struct Match2dOptions {
    double min_iou = 0.5;           ///< a match: IoU of projected box and label box, (0, 1]
    double hidden_min_cover = 0.7;  ///< a partly hidden label (occluded >= 1) also matches
                                    ///< when this share of its box lies in the entity's box
    double hidden_min_iou = 0.25;   ///< ... and their IoU is at least this, (0, 1]
    double min_height_px = 36.0;    ///< labels shorter than this are not owed, pixels
    int max_occluded = 1;           ///< labels more hidden than this are not owed
    double max_truncated = 0.5;     ///< labels more truncated than this are not owed
    double max_range_m = 30.0;      ///< unmatched entities farther than this (bird's-eye)
                                    ///< are not counted, metres
    double dont_care_cover = 0.5;   ///< an unmatched entity with this share of its box in a
                                    ///< don't-care region is not counted, (0, 1]
    /// Throws std::invalid_argument naming the bad field.
    void validate() const;
};

/// Counts of one category.
struct Counts2d {
    std::size_t owed = 0;     ///< labels owed (tall, visible and inside enough)
    std::size_t found = 0;    ///< of those, matched
    std::size_t counted = 0;  ///< entities counted: matched to an owed label, or unmatched in range
    std::size_t correct = 0;  ///< of those, matched to an owed label
    std::size_t ignored = 0;  ///< entities matched to a label not owed, in a don't-care region
                              ///< or unmatched beyond range
    Counts2d& operator+=(const Counts2d& other);
    std::size_t false_entities() const { return counted - correct; }
    double recall() const;     ///< found / owed (1 when none owed)
    double precision() const;  ///< correct / counted (1 when none counted)
};

/// One entity as scored.
struct Scored2d {
    std::size_t entity = 0;  ///< index into the entity list
    Category2d category = Category2d::vehicle;
    Eigen::Vector4d box_px = Eigen::Vector4d::Zero();  ///< projected, clipped to the image
    double range_m = 0.0;                              ///< bird's-eye distance from the camera
    std::optional<std::size_t> label;                  ///< matched label, index into objects
    double iou = 0.0;                                  ///< with the matched label
    enum class Outcome { correct, ignored, false_entity } outcome = Outcome::ignored;
};

/// The scores of one frame.
struct FrameScore2d {
    std::string frame;
    Counts2d counts[kCategory2dCount];
    std::vector<Scored2d> entities;   ///< entities of a category whose box is in the image
    std::vector<std::size_t> missed;  ///< owed labels without a match, indices into objects
};

/// Projects every entity of a category with `camera` and matches it to the frame's labels:
/// pairs of one category whose boxes meet the rule (IoU >= min_iou; for a partly hidden label
/// also cover >= hidden_min_cover with IoU >= hidden_min_iou) are taken greedily by IoU, one to
/// one. Throws std::invalid_argument when the camera has no focal length.
FrameScore2d score_frame_2d(const std::vector<scene_schema::Entity>& entities,
                            const scene_schema::CameraIntrinsics& camera,
                            const FrameLabels2d& labels, const Match2dOptions& options);

/// True when a label is owed under the options.
bool label_owed(const Label2d& label, const Match2dOptions& options);

}  // namespace cloud_analysis
