#include "scene_viewer/figure/grid_figure.hpp"

#include <cmath>
#include <cstring>
#include <stdexcept>

#include "scene_viewer/figure/bitmap_font.hpp"
#include "scene_viewer/render/image.hpp"

namespace scene_viewer {

void GridFigureOptions::validate() const {
    if (columns < 0) throw std::invalid_argument("columns must be >= 0");
    if (gap_px < 0 || gap_px > 1000) throw std::invalid_argument("gap_px must be in 0..1000");
    if (label_scale < 1 || label_scale > 16)
        throw std::invalid_argument("label_scale must be in 1..16");
}

ImageRgba8 compose_grid(const std::vector<ImageRgba8>& tiles,
                        const std::vector<std::string>& labels, const GridFigureOptions& options) {
    options.validate();
    if (tiles.empty()) throw std::invalid_argument("grid figure: no tiles");
    if (!labels.empty() && labels.size() != tiles.size())
        throw std::invalid_argument("grid figure: " + std::to_string(labels.size()) +
                                    " labels for " + std::to_string(tiles.size()) + " tiles");
    const int tw = tiles.front().width, th = tiles.front().height;
    for (const auto& t : tiles) {
        if (t.width != tw || t.height != th)
            throw std::invalid_argument("grid figure: tiles differ in size");
    }
    const int n = static_cast<int>(tiles.size());
    const int cols = options.columns > 0
                         ? std::min(options.columns, n)
                         : static_cast<int>(std::ceil(std::sqrt(static_cast<double>(n))));
    const int rows = (n + cols - 1) / cols;
    const int label_h = labels.empty() ? 0 : kGlyphHeight * options.label_scale + options.gap_px;
    const int cell_h = label_h + th;
    const int width = cols * tw + (cols + 1) * options.gap_px;
    const int height = rows * cell_h + (rows + 1) * options.gap_px;
    if (static_cast<long long>(width) * height > 16384LL * 16384LL)
        throw std::invalid_argument("grid figure: too large");
    ImageRgba8 figure = make_image(width, height, options.background);
    for (int i = 0; i < n; ++i) {
        const int x0 = options.gap_px + (i % cols) * (tw + options.gap_px);
        const int y0 = options.gap_px + (i / cols) * (cell_h + options.gap_px);
        if (!labels.empty()) {
            draw_text(figure, x0, y0, labels[static_cast<std::size_t>(i)], options.label_colour,
                      options.label_scale);
        }
        const ImageRgba8& tile = tiles[static_cast<std::size_t>(i)];
        for (int y = 0; y < th; ++y) {
            std::memcpy(
                &figure.pixels[(static_cast<std::size_t>(y0 + label_h + y) * width + x0) * 4],
                &tile.pixels[static_cast<std::size_t>(y) * tw * 4],
                static_cast<std::size_t>(tw) * 4);
        }
    }
    return figure;
}

}  // namespace scene_viewer
