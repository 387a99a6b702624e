#include <stdexcept>

#include "cloud_analysis/geometry/scene_geometry.hpp"

namespace cloud_analysis::geometry {

ImageU8 colour_classes(const ClassImage& classes, const Palette& palette) {
    ImageU8 out;
    out.width_px = classes.width_px;
    out.height_px = classes.height_px;
    out.channels = 3;
    out.data.assign(classes.class_index.size() * 3, 0);
    for (std::size_t i = 0; i < classes.class_index.size(); ++i) {
        const std::uint16_t c = classes.class_index[i];
        if (c >= palette.classes.size()) continue;
        const Rgb& rgb = palette.classes[c].colour;
        out.data[3 * i] = rgb[0];
        out.data[3 * i + 1] = rgb[1];
        out.data[3 * i + 2] = rgb[2];
    }
    return out;
}

SemanticScore score_semantics(const ClassImage& estimate, const ClassImage& reference,
                              const Palette& palette, const std::vector<std::string>& class_names) {
    if (estimate.width_px != reference.width_px || estimate.height_px != reference.height_px ||
        estimate.class_index.size() != reference.class_index.size()) {
        throw std::invalid_argument("semantic images differ in size");
    }
    SemanticScore score;
    std::size_t same = 0;
    std::vector<std::uint16_t> wanted;
    for (const auto& name : class_names) wanted.push_back(find_class(palette, name));
    std::vector<std::size_t> both(wanted.size(), 0), either(wanted.size(), 0);
    for (std::size_t i = 0; i < reference.class_index.size(); ++i) {
        const std::uint16_t r = reference.class_index[i];
        if (r == kVoidClass) continue;
        const std::uint16_t e = estimate.class_index[i];
        ++score.pixels;
        if (e == r) ++same;
        for (std::size_t k = 0; k < wanted.size(); ++k) {
            if (wanted[k] == kVoidClass) continue;
            const bool in_r = r == wanted[k], in_e = e == wanted[k];
            both[k] += in_r && in_e ? 1 : 0;
            either[k] += in_r || in_e ? 1 : 0;
        }
    }
    score.accuracy = score.pixels ? static_cast<double>(same) / score.pixels : 0.0;
    for (std::size_t k = 0; k < wanted.size(); ++k) {
        score.iou.emplace_back(class_names[k],
                               either[k] ? static_cast<double>(both[k]) / either[k] : -1.0);
    }
    return score;
}

}  // namespace cloud_analysis::geometry
