#include "scene_viewer/assets/palette.hpp"

#include <stdexcept>
#include <string>

namespace scene_viewer {

namespace {

// The Cityscapes classes the renderer draws: names, labelIds and colours generated from
// assets/palettes/cityscapes.json (scene_viewer/CMakeLists.txt), ground patches marked.
constexpr PaletteEntry kCityscapes[] = {
#include "scene_viewer/cityscapes_table.inc"
};

}  // namespace

std::optional<PaletteEntry> cityscapes_by_id(int class_id) {
    for (const auto& e : kCityscapes) {
        if (e.class_id == class_id) return e;
    }
    return std::nullopt;
}

std::optional<PaletteEntry> cityscapes_by_name(std::string_view name) {
    for (const auto& e : kCityscapes) {
        if (name == e.name) return e;
    }
    return std::nullopt;
}

Rgb8 class_colour(int class_id, std::string_view class_name) {
    if (auto e = cityscapes_by_id(class_id)) return e->colour;
    if (auto e = cityscapes_by_name(class_name)) return e->colour;
    return kUnknownColour;
}

bool is_ground_class(int class_id, std::string_view class_name) {
    if (auto e = cityscapes_by_id(class_id)) return e->ground;
    if (auto e = cityscapes_by_name(class_name)) return e->ground;
    return false;
}

bool has_instances(int class_id) { return class_id >= 24 && class_id <= 33; }

std::vector<std::uint16_t> kitti_instance_ids(const std::vector<int>& class_ids) {
    std::vector<std::uint16_t> ids;
    ids.reserve(class_ids.size());
    int counts[256] = {};
    for (int c : class_ids) {
        if (c < 0 || c > 255)
            throw std::invalid_argument("class_id " + std::to_string(c) +
                                        " does not fit KITTI's 8-bit labelId");
        int n = 0;
        if (has_instances(c)) {
            n = ++counts[c];
            if (n > 255)
                throw std::invalid_argument("more than 255 instances of class_id " +
                                            std::to_string(c) + " (KITTI's 8-bit instance index)");
        }
        ids.push_back(static_cast<std::uint16_t>(c << 8 | n));
    }
    return ids;
}

}  // namespace scene_viewer
