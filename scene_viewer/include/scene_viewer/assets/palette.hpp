#pragma once

/// The Cityscapes semantic palette (labelId -> name, colour), used for semantic shading so a
/// rendered pixel can be compared with a semantic image exactly.

#include <array>
#include <cstdint>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

namespace scene_viewer {

using Rgb8 = std::array<std::uint8_t, 3>;

struct PaletteEntry {
    int class_id;      ///< Cityscapes labelId
    const char* name;  ///< Cityscapes class name
    Rgb8 colour;       ///< Cityscapes colour
    bool ground;       ///< drawn as a flat ground patch (road, sidewalk, terrain...)
};

/// Entry of a Cityscapes labelId, if it is one of the palette's classes.
std::optional<PaletteEntry> cityscapes_by_id(int class_id);
/// Entry of a Cityscapes class name ("car"), if known.
std::optional<PaletteEntry> cityscapes_by_name(std::string_view name);

/// Colour of an entity: by class id, else by class name, else kUnknownColour.
Rgb8 class_colour(int class_id, std::string_view class_name);
/// True for stuff classes drawn as ground patches (road, sidewalk, parking, terrain...).
bool is_ground_class(int class_id, std::string_view class_name);

/// True for Cityscapes classes with instances (person 24 .. bicycle 33).
bool has_instances(int class_id);

/// KITTI instance ids of a document's entities, in file order: labelId << 8 | n, n counting
/// 1..255 per class; classes without instances get labelId << 8. Throws std::invalid_argument
/// for a class id outside 0..255 or more than 255 instances of one class.
std::vector<std::uint16_t> kitti_instance_ids(const std::vector<int>& class_ids);

/// Colour of classes the palette does not know (magenta, easy to spot).
inline constexpr Rgb8 kUnknownColour{255, 0, 255};

}  // namespace scene_viewer
