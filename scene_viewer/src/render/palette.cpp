#include "scene_viewer/render/palette.hpp"

#include <stdexcept>
#include <string>

namespace scene_viewer {

namespace {

// Cityscapes labels (cityscapesScripts helpers/labels.py), the classes the project uses.
constexpr PaletteEntry kCityscapes[] = {
    {7, "road", {128, 64, 128}, true},
    {8, "sidewalk", {244, 35, 232}, true},
    {9, "parking", {250, 170, 160}, true},
    {10, "rail track", {230, 150, 140}, true},
    {11, "building", {70, 70, 70}, false},
    {12, "wall", {102, 102, 156}, false},
    {13, "fence", {190, 153, 153}, false},
    {17, "pole", {153, 153, 153}, false},
    {19, "traffic light", {250, 170, 30}, false},
    {20, "traffic sign", {220, 220, 0}, false},
    {21, "vegetation", {107, 142, 35}, false},
    {22, "terrain", {152, 251, 152}, true},
    {23, "sky", {70, 130, 180}, false},
    {24, "person", {220, 20, 60}, false},
    {25, "rider", {255, 0, 0}, false},
    {26, "car", {0, 0, 142}, false},
    {27, "truck", {0, 0, 70}, false},
    {28, "bus", {0, 60, 100}, false},
    {31, "train", {0, 80, 100}, false},
    {32, "motorcycle", {0, 0, 230}, false},
    {33, "bicycle", {119, 11, 32}, false},
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
