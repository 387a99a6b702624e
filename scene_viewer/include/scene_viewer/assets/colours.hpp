#pragma once

/// Colours of what is not an entity class (class colours come from the palette, palette.hpp).

#include "scene_viewer/assets/palette.hpp"

namespace scene_viewer {

/// Colours that are not classes: background of lit and semantic renders, ego car.
inline constexpr Rgb8 kLitBackground{205, 215, 228};
inline constexpr Rgb8 kSemanticBackground{0, 0, 0};
inline constexpr Rgb8 kLitEgoColour{230, 230, 235};

}  // namespace scene_viewer
