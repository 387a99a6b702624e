#pragma once

/// A tiny built-in 5x7 bitmap font for figure labels (digits, letters, common punctuation;
/// lower case is drawn as upper case, unknown characters as a hollow box).

#include <string_view>

#include "scene_viewer/assets/model.hpp"
#include "scene_viewer/assets/palette.hpp"

namespace scene_viewer {

inline constexpr int kGlyphWidth = 5;    ///< glyph columns, pixels at scale 1
inline constexpr int kGlyphHeight = 7;   ///< glyph rows, pixels at scale 1
inline constexpr int kGlyphAdvance = 6;  ///< glyph width + 1 column of spacing

/// True when pixel (col, row) of the glyph of `c` is set.
bool glyph_pixel(char c, int col, int row);

/// Width in pixels of `text` at `scale`.
int text_width(std::string_view text, int scale);

/// Draws `text` with its top-left corner at (x, y), each font pixel a scale x scale block;
/// clipped to the image.
void draw_text(ImageRgba8& image, int x, int y, std::string_view text, Rgb8 colour, int scale);

}  // namespace scene_viewer
