#pragma once

/// Figures: several renders of the same size laid out in a labelled grid.

#include <string>
#include <vector>

#include "scene_viewer/assets/model.hpp"
#include "scene_viewer/assets/palette.hpp"

namespace scene_viewer {

struct GridFigureOptions {
    int columns = 0;                 ///< tiles per row; 0 = ceil(sqrt(tile count))
    int gap_px = 8;                  ///< space between tiles and around the figure, pixels
    int label_scale = 2;             ///< font pixel size, pixels (5x7 glyphs)
    Rgb8 background{255, 255, 255};  ///< figure background
    Rgb8 label_colour{20, 20, 20};   ///< label text colour
    /// Throws std::invalid_argument naming the bad field.
    void validate() const;
};

/// Lays out `tiles` (all the same size) row by row, each with its label above it. `labels` is
/// empty or has one entry per tile.
ImageRgba8 compose_grid(const std::vector<ImageRgba8>& tiles,
                        const std::vector<std::string>& labels, const GridFigureOptions& options);

}  // namespace scene_viewer
