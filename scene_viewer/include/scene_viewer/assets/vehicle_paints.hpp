#pragma once

/// Paints of vehicles in sensor renders: the colours of the world's cars, so that a rendered
/// street does not teach that every car is the class colour.

#include <cstdint>
#include <string_view>
#include <vector>

#include "scene_viewer/assets/palette.hpp"

namespace scene_viewer {

/// One paint and its share of the world's new cars.
struct VehiclePaint {
    const char* name;  ///< "white", "black", ...
    Rgb8 srgb;         ///< body colour, sRGB 0..255
    double share;      ///< share of cars, 0..1 (the table's shares sum to 1)
};

/// The paints: the shares of the Axalta Global Automotive Color Popularity Report 2022 (world:
/// white 35 %, black 19 %, grey 19 %, silver 10 %, blue 7 %, red 6 %, beige and brown 2 %,
/// green 1 %, yellow and gold 1 %).
const std::vector<VehiclePaint>& vehicle_paints();

/// The paint of the vehicle with this entity id: drawn by the shares from a hash of `seed` and
/// the id (FNV-1a, then MurmurHash3's finaliser), so one vehicle keeps its paint over a drive,
/// the same scene and seed render the same, and "car-1" of one seed is not "car-1" of another.
const VehiclePaint& vehicle_paint(std::string_view entity_id, std::uint64_t seed);

/// Whether entities of this class wear a paint (car, truck, bus, motorcycle).
bool is_painted_class(std::string_view class_name);

}  // namespace scene_viewer
