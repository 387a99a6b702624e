#include "scene_viewer/ecs/render_options.hpp"

#include <algorithm>
#include <stdexcept>

namespace scene_viewer {

Shading parse_shading(const std::string& name) {
    if (name == "lit") return Shading::lit;
    if (name == "semantic") return Shading::semantic;
    if (name == "instance") return Shading::instance;
    throw std::invalid_argument("unknown shading '" + name + "' (lit, semantic, instance)");
}

Antialias parse_antialias(const std::string& name) {
    if (name == "fxaa") return Antialias::fxaa;
    if (name == "msaa") return Antialias::msaa;
    if (name == "none") return Antialias::none;
    throw std::invalid_argument("unknown antialiasing '" + name + "' (fxaa, msaa, none)");
}

void RenderOptions::validate() const {
    if (width_px < 1 || width_px > kMaxImageSide)
        throw std::invalid_argument("width_px must be in 1.." + std::to_string(kMaxImageSide));
    if (height_px < 1 || height_px > kMaxImageSide)
        throw std::invalid_argument("height_px must be in 1.." + std::to_string(kMaxImageSide));
    if (msaa_samples < 0 || msaa_samples > 16)
        throw std::invalid_argument("msaa_samples must be in 0..16");
    // FXAA renders into a second single-sample target: it counts as 2 samples.
    const bool lit = shading == Shading::lit;
    const int samples_per_pixel = !lit                           ? 1
                                  : antialias == Antialias::msaa ? std::max(1, msaa_samples)
                                  : antialias == Antialias::fxaa ? 2
                                                                 : 1;
    if (static_cast<long long>(width_px) * height_px * samples_per_pixel > kMaxFrameSamples)
        throw std::invalid_argument("width_px * height_px * msaa_samples (2 for fxaa) must be <= " +
                                    std::to_string(kMaxFrameSamples) +
                                    " (lower --size or --msaa, or --antialias none)");
    if (!(point_size_px >= 1.0f && point_size_px <= 64.0f))
        throw std::invalid_argument("point_size_px must be in 1..64");
    view.validate();
}

}  // namespace scene_viewer
