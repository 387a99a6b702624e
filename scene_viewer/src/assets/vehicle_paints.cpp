#include "scene_viewer/assets/vehicle_paints.hpp"

#include <cstdint>

namespace scene_viewer {

const std::vector<VehiclePaint>& vehicle_paints() {
    static const std::vector<VehiclePaint> paints = {
        {"white", {232, 232, 228}, 0.35}, {"black", {22, 22, 24}, 0.19},
        {"grey", {98, 100, 104}, 0.19},   {"silver", {170, 173, 178}, 0.10},
        {"blue", {28, 52, 112}, 0.07},    {"red", {140, 22, 22}, 0.06},
        {"beige", {120, 95, 70}, 0.02},   {"green", {34, 70, 44}, 0.01},
        {"yellow", {200, 160, 30}, 0.01},
    };
    return paints;
}

const VehiclePaint& vehicle_paint(std::string_view entity_id, std::uint64_t seed) {
    std::uint64_t h = 14695981039346656037ull;  // FNV-1a, 64 bits
    const auto add = [&h](unsigned char byte) {
        h ^= byte;
        h *= 1099511628211ull;
    };
    for (int b = 0; b < 8; ++b) add(static_cast<unsigned char>(seed >> (8 * b)));
    for (const char c : entity_id) add(static_cast<unsigned char>(c));
    // FNV-1a barely stirs the top bits for ids that differ in their last character ("car-1",
    // "car-2"): MurmurHash3's finaliser mixes every bit into every other first.
    h ^= h >> 33;
    h *= 0xff51afd7ed558ccdull;
    h ^= h >> 33;
    h *= 0xc4ceb9fe1a85ec53ull;
    h ^= h >> 33;
    // The top 53 bits as a uniform draw in [0, 1).
    const double draw = static_cast<double>(h >> 11) / 9007199254740992.0;
    const std::vector<VehiclePaint>& paints = vehicle_paints();
    double cumulative = 0.0;
    for (const VehiclePaint& p : paints) {
        cumulative += p.share;
        if (draw < cumulative) return p;
    }
    return paints.back();
}

bool is_painted_class(std::string_view class_name) {
    return class_name == "car" || class_name == "truck" || class_name == "bus" ||
           class_name == "motorcycle";
}

}  // namespace scene_viewer
