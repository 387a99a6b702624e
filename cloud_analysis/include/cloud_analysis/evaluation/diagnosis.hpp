#pragma once

/// Why a scored object was missed or boxed badly and why a box is spurious, one line each, so a
/// failure is diagnosed in one look: a missed car merged with which neighbour into which box,
/// a car under-covered by how much, a phantom over what. For both evaluations: entity to
/// entity (a rendered scene's truth) and cars against KITTI's instance image. See
/// docs/evaluation.md "Diagnosis".

#include <cstdint>
#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include <scene_schema/entities.hpp>

#include "cloud_analysis/cloud/types.hpp"
#include "cloud_analysis/evaluation/entity_eval.hpp"
#include "cloud_analysis/evaluation/evaluate.hpp"

namespace cloud_analysis {

/// One diagnosed object.
struct Diagnosis {
    std::string id;      ///< the reference's (GT car's) id, or the spurious estimate's
    std::string kind;    ///< merged, off-centre, other-class, no-box, under-covered,
                         ///< too-large, spans, duplicate, phantom, stuff-on-thing
    std::string reason;  ///< one line for people, naming the other objects involved
};

/// Reasons for every missed reference, every match under the IoU threshold and every spurious
/// estimate of `ev` (evaluate_entities on the same lists). `visibility` (per reference, may be
/// empty) adds the visible share to the missed lines.
std::vector<Diagnosis> diagnose_entities(
    const std::vector<scene_schema::Entity>& reference,
    const std::vector<scene_schema::Entity>& estimate, const EntityEvaluation& ev,
    const std::vector<std::optional<ReferenceVisibility>>& visibility = {});

/// A KITTI instance image (uint16, labelId << 8 | instance), for what lies under a box.
struct InstanceImage {
    int width_px = 0;                     ///< image width
    int height_px = 0;                    ///< image height
    std::vector<std::uint16_t> values;    ///< row-major
    std::vector<std::string> label_name;  ///< labelId (0..255) -> class name, "" when unknown
};

/// Reads an instance PNG; class names from `palette` (ClassInfo::id is the labelId). Throws
/// std::runtime_error naming the file.
InstanceImage load_instance_image(const std::filesystem::path& instance_png,
                                  const Palette& palette);

/// Reasons for every owed GT car left unmatched and every car entity in range that matches no
/// GT car and is not unscorable (`ev` = evaluate_cars on the same lists). With `image` and
/// `camera`, a phantom names the classes of the instance image inside its projected box.
std::vector<Diagnosis> diagnose_cars(const std::vector<scene_schema::Entity>& entities,
                                     const std::vector<GtCar>& gt, const CarEvaluation& ev,
                                     const CarMatchOptions& options,
                                     const InstanceImage* image = nullptr,
                                     const StereoCamera* camera = nullptr);

}  // namespace cloud_analysis
