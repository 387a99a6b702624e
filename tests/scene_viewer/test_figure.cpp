#include <catch2/catch.hpp>

#include "scene_viewer/figure/bitmap_font.hpp"
#include "scene_viewer/figure/grid_figure.hpp"
#include "scene_viewer/render/image.hpp"

using namespace scene_viewer;

namespace {
int set_pixels(char c) {
    int n = 0;
    for (int r = 0; r < kGlyphHeight; ++r)
        for (int col = 0; col < kGlyphWidth; ++col) n += glyph_pixel(c, col, r) ? 1 : 0;
    return n;
}
bool same_glyph(char a, char b) {
    for (int r = 0; r < kGlyphHeight; ++r)
        for (int col = 0; col < kGlyphWidth; ++col)
            if (glyph_pixel(a, col, r) != glyph_pixel(b, col, r)) return false;
    return true;
}
}  // namespace

TEST_CASE("Glyphs have their known shapes: I has a full middle column, space is empty",
          "[figure]") {
    CHECK(set_pixels(' ') == 0);
    for (int r = 0; r < kGlyphHeight; ++r) CHECK(glyph_pixel('I', 2, r));
    CHECK(glyph_pixel('-', 0, 3));
    CHECK_FALSE(glyph_pixel('-', 0, 2));
    // Lower case draws as upper case; every letter and digit has a glyph (not the hollow box).
    for (char c = 'a'; c <= 'z'; ++c) {
        if (c == 'x') continue;  // own glyph, for sizes like 1280x720
        CHECK(same_glyph(c, static_cast<char>(c - 'a' + 'A')));
    }
    for (char c : std::string("0123456789ABCDEFGHIJKLMNOPQRSTUVWXYZ")) {
        CHECK_FALSE(same_glyph(c, '\x01'));
    }
    CHECK_FALSE(same_glyph('O', '0'));
}

TEST_CASE("Text is drawn at its position and scale and clipped at the image border", "[figure]") {
    ImageRgba8 image = make_image(40, 20, {255, 255, 255});
    draw_text(image, 2, 3, "I", {0, 0, 0}, 2);
    // The middle column of I (col 2) at scale 2 covers x = 6..7, y = 3..16.
    CHECK(pixel_at(image, 6, 3)[0] == 0);
    CHECK(pixel_at(image, 7, 16)[0] == 0);
    CHECK(pixel_at(image, 6, 17)[0] == 255);
    CHECK(text_width("AB", 2) == 22);
    draw_text(image, 35, 15, "WWW", {0, 0, 0}, 3);  // must not write out of bounds
}

TEST_CASE("The grid figure lays tiles out row by row under their labels", "[figure]") {
    std::vector<ImageRgba8> tiles = {make_image(10, 6, {255, 0, 0}), make_image(10, 6, {0, 255, 0}),
                                     make_image(10, 6, {0, 0, 255})};
    GridFigureOptions options;
    options.columns = 2;
    options.gap_px = 2;
    options.label_scale = 1;
    const ImageRgba8 fig = compose_grid(tiles, {"A", "B", "C"}, options);
    // 2 columns: 2*10 + 3*2 = 26 wide; 2 rows of (7 + 2 label + 6 tile) + 3*2 gaps = 36 high.
    CHECK(fig.width == 26);
    CHECK(fig.height == 36);
    const int label_h = kGlyphHeight + 2;
    CHECK(pixel_at(fig, 2, 2 + label_h)[0] == 255);                    // red tile, top-left
    CHECK(pixel_at(fig, 14, 2 + label_h)[1] == 255);                   // green tile, top-right
    CHECK(pixel_at(fig, 2, 2 + label_h + 6 + 2 + label_h)[2] == 255);  // blue tile, 2nd row
    CHECK_THROWS_WITH(compose_grid(tiles, {"A"}, options), Catch::Contains("labels"));
}
