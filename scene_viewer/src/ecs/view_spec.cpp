#include "scene_viewer/ecs/view_spec.hpp"

#include <stdexcept>

namespace scene_viewer {

ViewKind parse_view_kind(const std::string& name) {
    if (name == "camera") return ViewKind::camera;
    if (name == "chase") return ViewKind::chase;
    if (name == "bev") return ViewKind::bev;
    if (name == "free") return ViewKind::free;
    throw std::invalid_argument("unknown view '" + name + "' (camera, chase, bev, free)");
}

const char* to_string(ViewKind kind) {
    switch (kind) {
        case ViewKind::camera:
            return "camera";
        case ViewKind::chase:
            return "chase";
        case ViewKind::bev:
            return "bev";
        case ViewKind::free:
            return "free";
    }
    return "?";
}

void ViewSpec::validate() const {
    if (!(fov_y_deg > 1.0f && fov_y_deg < 179.0f))
        throw std::invalid_argument("fov_y_deg must be in (1, 179) degrees");
    if (!(near_m > 0.0f)) throw std::invalid_argument("near_m must be > 0");
    if (!(far_m > near_m)) throw std::invalid_argument("far_m must be > near_m");
    if (!(bev_half_height_m > 0.0f)) throw std::invalid_argument("bev_half_height_m must be > 0");
    if (kind == ViewKind::free || kind == ViewKind::chase) {
        if (glm::length(target_kitti - eye_kitti) < 1e-6f)
            throw std::invalid_argument("eye and target must differ");
    }
}

}  // namespace scene_viewer
