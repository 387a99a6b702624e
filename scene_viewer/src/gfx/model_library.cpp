#include "scene_viewer/gfx/model_library.hpp"

#include <algorithm>
#include <cmath>

namespace scene_viewer {

namespace {

/// glTF base colours are linear; the framebuffer is not sRGB, so encode for display here.
glm::vec4 display_colour(const glm::vec4& linear) {
    glm::vec4 c = linear;
    for (int i = 0; i < 3; ++i) {
        const float v = std::clamp(linear[i], 0.0f, 1.0f);
        c[i] = v <= 0.0031308f ? 12.92f * v : 1.055f * std::pow(v, 1.0f / 2.4f) - 0.055f;
    }
    return c;
}

}  // namespace

ModelLibrary::~ModelLibrary() {
    for (const auto& m : models_) release(m);
}

void ModelLibrary::release(const UploadedModel& model) {
    for (const auto& p : model.primitives) device_->destroy_mesh(p.mesh);
    for (const auto& t : model.textures) device_->destroy_texture(t);
}

std::uint32_t ModelLibrary::store(UploadedModel model) {
    auto it = index_.find(model.key);
    if (it != index_.end()) {
        release(models_[it->second]);
        models_[it->second] = std::move(model);
        return it->second;
    }
    const auto index = static_cast<std::uint32_t>(models_.size());
    index_[model.key] = index;
    models_.push_back(std::move(model));
    return index;
}

std::uint32_t ModelLibrary::put(const std::string& key, const Model& model) {
    UploadedModel up;
    up.key = key;
    up.bounds_min = model.bounds_min;
    up.bounds_max = model.bounds_max;
    for (const auto& t : model.textures) up.textures.push_back(device_->create_texture(t));
    const std::vector<TextureHandle>& textures = up.textures;
    for (const auto& prim : model.primitives) {
        MeshData data;
        data.positions = prim.positions;
        data.normals = prim.normals;
        data.indices = prim.indices;
        UploadedPrimitive p;
        if (prim.texture >= 0 && prim.texture < static_cast<int>(textures.size()) &&
            prim.texcoords.size() == prim.positions.size()) {
            data.texcoords = prim.texcoords;
            p.texture = textures[static_cast<std::size_t>(prim.texture)];
        }
        p.mesh = device_->create_mesh(data);
        p.base_colour = display_colour(prim.base_colour);
        p.node_transform = prim.node_transform;
        p.paint = prim.material_name == "paint";
        up.triangle_count +=
            (prim.indices.empty() ? prim.positions.size() : prim.indices.size()) / 3;
        up.primitives.push_back(p);
    }
    return store(std::move(up));
}

std::uint32_t ModelLibrary::put(const std::string& key, const MeshData& mesh) {
    UploadedModel up;
    up.key = key;
    if (!mesh.positions.empty()) {
        up.bounds_min = up.bounds_max = mesh.positions.front();
        for (const auto& p : mesh.positions) {
            up.bounds_min = glm::min(up.bounds_min, p);
            up.bounds_max = glm::max(up.bounds_max, p);
        }
    }
    if (mesh.topology == Topology::triangles) {
        up.triangle_count =
            (mesh.indices.empty() ? mesh.positions.size() : mesh.indices.size()) / 3;
    }
    UploadedPrimitive p;
    p.mesh = device_->create_mesh(mesh);
    up.primitives.push_back(p);
    return store(std::move(up));
}

std::optional<std::uint32_t> ModelLibrary::find(const std::string& key) const {
    auto it = index_.find(key);
    if (it == index_.end()) return std::nullopt;
    return it->second;
}

MeshData unit_box_mesh() {
    MeshData m;
    const glm::vec3 normals[6] = {{1, 0, 0},  {-1, 0, 0}, {0, 1, 0},
                                  {0, -1, 0}, {0, 0, 1},  {0, 0, -1}};
    for (const auto& n : normals) {
        // Two axes spanning the face, chosen so (u x v) = n (counter-clockwise from outside).
        const glm::vec3 u = std::abs(n.y) > 0.5f ? glm::vec3(0, 0, n.y) : glm::vec3(-n.z, 0, n.x);
        const glm::vec3 v = glm::cross(n, u);
        const auto base = static_cast<std::uint32_t>(m.positions.size());
        constexpr float kCorners[4][2] = {{-1, -1}, {1, -1}, {1, 1}, {-1, 1}};
        for (const auto& c : kCorners) {
            m.positions.push_back(0.5f * (n + c[0] * u + c[1] * v));
            m.normals.push_back(n);
        }
        for (std::uint32_t i : {0u, 1u, 2u, 0u, 2u, 3u}) m.indices.push_back(base + i);
    }
    return m;
}

}  // namespace scene_viewer
