#pragma once

/// Models uploaded to a device, named by a key (class name, "box", "grid", "cloud"). Upload is
/// separate from loading: the library takes CPU data (Model, MeshData) and keeps the handles for
/// as many frames as the process renders.

#include <cstdint>
#include <optional>
#include <string>
#include <unordered_map>
#include <vector>

#include <glm/glm.hpp>

#include "scene_viewer/assets/model.hpp"
#include "scene_viewer/gfx/device.hpp"

namespace scene_viewer {

/// One primitive as uploaded.
struct UploadedPrimitive {
    MeshHandle mesh;
    TextureHandle texture;
    glm::vec4 base_colour{1.0f};  ///< display (sRGB-encoded) RGBA 0..1 of the glTF base colour
    glm::mat4 node_transform{1.0f};
    bool paint = false;  ///< its glTF material is named "paint": a vehicle's paint may replace it
};

/// A model as uploaded, with the bounds used to fit it into an entity box.
struct UploadedModel {
    std::string key;
    std::vector<UploadedPrimitive> primitives;
    std::vector<TextureHandle> textures;  ///< owned by this model, freed with it
    glm::vec3 bounds_min{-0.5f};
    glm::vec3 bounds_max{0.5f};
    std::size_t triangle_count = 0;
};

class ModelLibrary {
  public:
    explicit ModelLibrary(Device& device) : device_(&device) {}
    ~ModelLibrary();
    ModelLibrary(const ModelLibrary&) = delete;
    ModelLibrary& operator=(const ModelLibrary&) = delete;

    /// Uploads a model under `key`, replacing (and freeing) an earlier one; returns its index.
    std::uint32_t put(const std::string& key, const Model& model);
    /// Uploads one mesh as a model under `key`, replacing an earlier one.
    std::uint32_t put(const std::string& key, const MeshData& mesh);
    /// Index of the model under `key`.
    std::optional<std::uint32_t> find(const std::string& key) const;
    const UploadedModel& at(std::uint32_t index) const { return models_.at(index); }
    std::size_t size() const { return models_.size(); }

  private:
    std::uint32_t store(UploadedModel model);
    void release(const UploadedModel& model);
    Device* device_;
    std::vector<UploadedModel> models_;
    std::unordered_map<std::string, std::uint32_t> index_;
};

/// The unit cube [-0.5, 0.5]^3 with face normals (24 vertices, 12 triangles).
MeshData unit_box_mesh();

}  // namespace scene_viewer
