#include "scene_viewer/assets/scene_export.hpp"

#include <cmath>
#include <limits>
#include <map>
#include <sstream>
#include <stdexcept>
#include <string_view>
#include <utility>

#include <tiny_gltf.h>

#include "gltf_internal.hpp"
#include "scene_viewer/assets/image_io.hpp"
#include "stereoscene/support/atomic_file.hpp"

namespace scene_viewer {
namespace {

constexpr int kArrayBuffer = 34962;         // GL_ARRAY_BUFFER
constexpr int kElementArrayBuffer = 34963;  // GL_ELEMENT_ARRAY_BUFFER

bool finite(const glm::mat4& m) {
    for (int c = 0; c < 4; ++c) {
        for (int r = 0; r < 4; ++r) {
            if (!std::isfinite(m[c][r])) return false;
        }
    }
    return true;
}

bool is_identity(const glm::mat4& m) { return m == glm::mat4(1.0f); }

/// Builds the tinygltf document: one BIN buffer filled as accessors are added.
class Builder {
  public:
    Builder() {
        gltf_.asset.version = "2.0";
        gltf_.asset.generator = "stereoscene scene-render";
        gltf_.buffers.emplace_back();
    }

    int mesh_for(const Model& model) {
        const auto found = meshes_.find(&model);
        if (found != meshes_.end()) return found->second;
        tinygltf::Mesh mesh;
        mesh.name = model.name;
        for (const MeshPrimitive& p : model.primitives) {
            if (p.indices.empty()) continue;
            mesh.primitives.push_back(primitive(model, p));
        }
        gltf_.meshes.push_back(std::move(mesh));
        const int index = static_cast<int>(gltf_.meshes.size()) - 1;
        meshes_.emplace(&model, index);
        return index;
    }

    void add_node(const PlacedModel& placed) {
        tinygltf::Node node;
        node.name = placed.name;
        node.mesh = mesh_for(*placed.model);
        if (!is_identity(placed.world)) {
            node.matrix.resize(16);
            for (int i = 0; i < 16; ++i)
                node.matrix[static_cast<std::size_t>(i)] = placed.world[i / 4][i % 4];
        }
        gltf_.nodes.push_back(std::move(node));
    }

    tinygltf::Model finish() {
        tinygltf::Scene scene;
        scene.name = "scene";
        for (std::size_t i = 0; i < gltf_.nodes.size(); ++i)
            scene.nodes.push_back(static_cast<int>(i));
        gltf_.scenes.push_back(std::move(scene));
        gltf_.defaultScene = 0;
        if (gltf_.buffers[0].data.empty()) gltf_.buffers.clear();
        return std::move(gltf_);
    }

  private:
    int add_view(const void* data, std::size_t size, int target) {
        return gltf_detail::append_buffer_view(gltf_, data, size, target);
    }

    template <typename T>
    int add_accessor(const std::vector<T>& values, int type, int component_type, int target) {
        tinygltf::Accessor accessor;
        accessor.bufferView = add_view(values.data(), values.size() * sizeof(T), target);
        accessor.componentType = component_type;
        accessor.count = values.size();
        accessor.type = type;
        gltf_.accessors.push_back(std::move(accessor));
        return static_cast<int>(gltf_.accessors.size()) - 1;
    }

    /// The glTF image of a model's texture, embedded once as PNG.
    int image_for(const Model& model, int texture) {
        const auto key = std::make_pair(&model, texture);
        const auto found = images_.find(key);
        if (found != images_.end()) return found->second;
        const std::vector<unsigned char> png =
            encode_png(model.textures.at(static_cast<std::size_t>(texture)), 6);
        tinygltf::Image image;
        image.bufferView = add_view(png.data(), png.size(), 0);
        image.mimeType = "image/png";
        gltf_.images.push_back(std::move(image));
        const int index = static_cast<int>(gltf_.images.size()) - 1;
        images_.emplace(key, index);
        return index;
    }

    int sampler_for(const TextureSampler& s) {
        const auto found = samplers_.find(s);
        if (found != samplers_.end()) return found->second;
        tinygltf::Sampler sampler;
        sampler.magFilter = s.mag_filter;
        sampler.minFilter = s.min_filter;
        sampler.wrapS = s.wrap_s;
        sampler.wrapT = s.wrap_t;
        gltf_.samplers.push_back(sampler);
        const int index = static_cast<int>(gltf_.samplers.size()) - 1;
        samplers_.emplace(s, index);
        return index;
    }

    /// The glTF texture of a model's texture with a sampler.
    int texture_for(const Model& model, int texture, const TextureSampler& sampler) {
        const int image = image_for(model, texture);
        const auto key = std::make_pair(image, sampler);
        const auto found = textures_.find(key);
        if (found != textures_.end()) return found->second;
        tinygltf::Texture tex;
        tex.source = image;
        tex.sampler = sampler_for(sampler);
        gltf_.textures.push_back(tex);
        const int index = static_cast<int>(gltf_.textures.size()) - 1;
        textures_.emplace(key, index);
        return index;
    }

    /// The glTF material of a primitive: its base colour and texture, and the properties the
    /// model's file gave (MaterialProperties).
    tinygltf::Material material_of(const Model& model, const MeshPrimitive& p, bool textured) {
        tinygltf::Material material;
        material.name = p.material_name;
        material.pbrMetallicRoughness.baseColorFactor = {p.base_colour.r, p.base_colour.g,
                                                         p.base_colour.b, p.base_colour.a};
        material.pbrMetallicRoughness.metallicFactor = p.material.metallic;
        material.pbrMetallicRoughness.roughnessFactor = p.material.roughness;
        material.doubleSided = p.material.double_sided;
        material.alphaMode = p.material.alpha_mode;
        if (material.alphaMode == "OPAQUE" && p.base_colour.a < 1.0f) material.alphaMode = "BLEND";
        if (material.alphaMode == "MASK") material.alphaCutoff = p.material.alpha_cutoff;
        if (p.material.emissive != glm::vec3(0.0f)) {
            material.emissiveFactor = {p.material.emissive.r, p.material.emissive.g,
                                       p.material.emissive.b};
        }
        if (textured) {
            material.pbrMetallicRoughness.baseColorTexture.index =
                texture_for(model, p.texture, p.sampler);
        }
        return material;
    }

    tinygltf::Primitive primitive(const Model& model, const MeshPrimitive& p) {
        // The primitive's node transform is baked, so each model is one mesh in its own frame.
        std::vector<glm::vec3> positions = p.positions;
        std::vector<glm::vec3> normals = p.normals;
        if (!is_identity(p.node_transform)) {
            const glm::mat3 nm = glm::transpose(glm::inverse(glm::mat3(p.node_transform)));
            for (glm::vec3& v : positions) v = glm::vec3(p.node_transform * glm::vec4(v, 1.0f));
            for (glm::vec3& n : normals) n = glm::normalize(nm * n);
        }
        tinygltf::Primitive out;
        out.mode = TINYGLTF_MODE_TRIANGLES;
        const int pos = add_accessor(positions, TINYGLTF_TYPE_VEC3, TINYGLTF_COMPONENT_TYPE_FLOAT,
                                     kArrayBuffer);
        glm::vec3 lo(std::numeric_limits<float>::max());
        glm::vec3 hi(std::numeric_limits<float>::lowest());
        for (const glm::vec3& v : positions) {
            lo = glm::min(lo, v);
            hi = glm::max(hi, v);
        }
        gltf_.accessors[static_cast<std::size_t>(pos)].minValues = {lo.x, lo.y, lo.z};
        gltf_.accessors[static_cast<std::size_t>(pos)].maxValues = {hi.x, hi.y, hi.z};
        out.attributes["POSITION"] = pos;
        if (normals.size() == positions.size()) {
            out.attributes["NORMAL"] = add_accessor(normals, TINYGLTF_TYPE_VEC3,
                                                    TINYGLTF_COMPONENT_TYPE_FLOAT, kArrayBuffer);
        }
        if (p.texcoords.size() == positions.size()) {
            out.attributes["TEXCOORD_0"] = add_accessor(
                p.texcoords, TINYGLTF_TYPE_VEC2, TINYGLTF_COMPONENT_TYPE_FLOAT, kArrayBuffer);
        }
        out.indices = add_accessor(p.indices, TINYGLTF_TYPE_SCALAR,
                                   TINYGLTF_COMPONENT_TYPE_UNSIGNED_INT, kElementArrayBuffer);
        const bool textured = p.texture >= 0 &&
                              static_cast<std::size_t>(p.texture) < model.textures.size() &&
                              p.texcoords.size() == positions.size();
        gltf_.materials.push_back(material_of(model, p, textured));
        out.material = static_cast<int>(gltf_.materials.size()) - 1;
        return out;
    }

    tinygltf::Model gltf_;
    std::map<const Model*, int> meshes_;
    std::map<std::pair<const Model*, int>, int> images_;
    std::map<std::pair<int, TextureSampler>, int> textures_;
    std::map<TextureSampler, int> samplers_;
};

}  // namespace

std::vector<unsigned char> export_scene_glb_bytes(const std::vector<PlacedModel>& scene) {
    for (std::size_t i = 0; i < scene.size(); ++i) {
        if (scene[i].model == nullptr) {
            throw std::invalid_argument("export_scene_glb: scene[" + std::to_string(i) +
                                        "].model is null");
        }
        if (!finite(scene[i].world)) {
            throw std::invalid_argument("export_scene_glb: scene[" + std::to_string(i) +
                                        "].world is not finite");
        }
    }
    Builder builder;
    for (const PlacedModel& placed : scene) builder.add_node(placed);
    const tinygltf::Model gltf = builder.finish();
    tinygltf::TinyGLTF writer;
    std::ostringstream out;
    if (!writer.WriteGltfSceneToStream(&gltf, out, false, true)) {
        throw std::runtime_error("export_scene_glb: tinygltf could not serialise the scene");
    }
    const std::string bytes = out.str();
    return std::vector<unsigned char>(bytes.begin(), bytes.end());
}

void export_scene_glb(const std::vector<PlacedModel>& scene, const std::filesystem::path& path) {
    std::vector<unsigned char> bytes;
    try {
        bytes = export_scene_glb_bytes(scene);
    } catch (const std::exception& e) {
        throw std::runtime_error(path.string() + ": " + e.what());
    }
    // stereoscene::support::FileError (a std::runtime_error) already names the path.
    stereoscene::support::write_file_atomic(
        path, std::string_view(reinterpret_cast<const char*>(bytes.data()), bytes.size()));
}

}  // namespace scene_viewer
