#include "scene_viewer/render/render_setup.hpp"

#include <sstream>
#include <stdexcept>

#include "scene_viewer/render/image.hpp"

namespace scene_viewer {

std::pair<int, int> parse_image_size(const std::string& text) {
    std::stringstream ss(text);
    long long w = 0, h = 0;
    char x = 0;
    if (!(ss >> w >> x >> h) || (x != 'x' && x != 'X') || !(ss >> std::ws).eof()) {
        throw std::invalid_argument("expected WxH, got '" + text + "'");
    }
    if (w < 1 || h < 1 || w > kMaxImageSide || h > kMaxImageSide) {
        throw std::invalid_argument("each side must be in 1.." + std::to_string(kMaxImageSide) +
                                    ", got '" + text + "'");
    }
    return {static_cast<int>(w), static_cast<int>(h)};
}

glm::vec3 parse_point_m(const std::string& text) {
    std::stringstream ss(text);
    glm::vec3 v(0.0f);
    char comma = 0;
    if (!(ss >> v.x >> comma) || comma != ',' || !(ss >> v.y >> comma) || comma != ',' ||
        !(ss >> v.z) || !(ss >> std::ws).eof()) {
        throw std::invalid_argument("expected x,y,z in metres, got '" + text + "'");
    }
    return v;
}

std::pair<int, int> default_image_size(ViewKind kind,
                                       const scene_schema::EntityDocument& document) {
    if (kind == ViewKind::bev) return {800, 800};
    if (kind != ViewKind::camera) return {1280, 720};
    if (document.frame.camera) {
        return {document.frame.camera->width_px, document.frame.camera->height_px};
    }
    const RenderOptions defaults;
    return {defaults.width_px, defaults.height_px};
}

void share_view(const std::vector<scene_schema::EntityDocument>& documents,
                RenderOptions& options) {
    if (documents.empty()) throw std::invalid_argument("share_view: no documents");
    options.view.intrinsics = documents.front().frame.camera;
    if (options.view.kind != ViewKind::bev) return;
    scene_schema::EntityDocument all;
    for (const auto& d : documents) {
        all.entities.insert(all.entities.end(), d.entities.begin(), d.entities.end());
    }
    const ViewSpec fitted = bev_view_fitting(
        all, static_cast<float>(options.width_px) / static_cast<float>(options.height_px));
    options.view.bev_centre_xz = fitted.bev_centre_xz;
    options.view.bev_half_height_m = fitted.bev_half_height_m;
    options.fit_bev = false;
}

std::vector<std::string> classes_missing_models(const SceneRenderer& renderer,
                                                const ClassTable& table) {
    std::vector<std::string> out;
    for (const std::string& name : renderer.classes_drawn_as_boxes()) {
        const RenderClass* c = table.find(std::string_view(name));
        if (c != nullptr && c->kind == RenderKind::Block) continue;
        out.push_back(name);
    }
    return out;
}

void composite_background(ImageRgba8& render, const ImageRgba8& background, float opacity,
                          Shading shading) {
    composite_over(render, resize_nearest(background, render.width, render.height), opacity,
                   shading == Shading::lit ? kLitBackground : kSemanticBackground);
}

}  // namespace scene_viewer
