#include "scene_viewer/assets/gltf_loader.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <fstream>
#include <limits>
#include <new>
#include <stdexcept>
#include <string>
#include <system_error>
#include <utility>
#include <vector>

#include <tiny_gltf.h>
#include <glm/gtc/matrix_transform.hpp>
#include <glm/gtc/quaternion.hpp>
#include <nlohmann/json.hpp>

#include "scene_viewer/assets/image_io.hpp"
#include "stereoscene/support/limits.hpp"

#include "gltf_internal.hpp"

namespace scene_viewer {
namespace {

namespace fs = std::filesystem;
using namespace gltf_detail;

/// Indices a model may hold per vertex of the vertex limit (a closed triangle mesh has about
/// six).
constexpr std::uint64_t kIndicesPerVertex = 8;

/// Converts tinygltf's document into our Model: walks the scene's node forest, bakes transforms.
class Converter {
  public:
    Converter(const tinygltf::Model& gltf, Model& out) : gltf_(gltf), out_(out) {
        texture_slot_.assign(gltf.images.size(), -1);
        visited_.assign(gltf.nodes.size(), false);
    }

    void run() {
        std::vector<int> roots;
        int scene = gltf_.defaultScene;
        if (scene < 0 && !gltf_.scenes.empty()) scene = 0;
        if (scene >= static_cast<int>(gltf_.scenes.size())) {
            throw LoadError("default scene " + std::to_string(scene) + " does not exist");
        }
        if (scene >= 0) {
            roots = gltf_.scenes[static_cast<std::size_t>(scene)].nodes;
        } else {
            std::vector<bool> is_child(gltf_.nodes.size(), false);
            for (const tinygltf::Node& node : gltf_.nodes) {
                for (int child : node.children) {
                    if (child >= 0 && static_cast<std::size_t>(child) < is_child.size()) {
                        is_child[static_cast<std::size_t>(child)] = true;
                    }
                }
            }
            for (std::size_t i = 0; i < gltf_.nodes.size(); ++i) {
                if (!is_child[i]) roots.push_back(static_cast<int>(i));
            }
        }
        for (int root : roots) {
            visit(root, glm::mat4(1.0f));
        }
    }

  private:
    /// Walks one tree of the node forest depth first with an explicit stack, so a chain of
    /// nodes as deep as the file likes cannot overflow the call stack.
    void visit(int root, const glm::mat4& root_parent) {
        std::vector<std::pair<int, glm::mat4>> stack{{root, root_parent}};
        while (!stack.empty()) {
            const auto [index, parent] = stack.back();
            stack.pop_back();
            if (index < 0 || static_cast<std::size_t>(index) >= gltf_.nodes.size()) {
                throw LoadError("node " + std::to_string(index) + " does not exist");
            }
            if (visited_[static_cast<std::size_t>(index)]) {
                throw LoadError("node " + std::to_string(index) +
                                " is reached twice: the node hierarchy is not a forest");
            }
            visited_[static_cast<std::size_t>(index)] = true;
            const tinygltf::Node& node = gltf_.nodes[static_cast<std::size_t>(index)];
            const glm::mat4 world = parent * local_transform(node);
            if (node.mesh >= 0) {
                if (static_cast<std::size_t>(node.mesh) >= gltf_.meshes.size()) {
                    throw LoadError("node " + std::to_string(index) + ": mesh " +
                                    std::to_string(node.mesh) + " does not exist");
                }
                add_mesh(node.mesh, world);
            }
            // Reversed, so children are converted in their listed order.
            for (auto child = node.children.rbegin(); child != node.children.rend(); ++child) {
                stack.emplace_back(*child, world);
            }
        }
    }

    /// Counts an accessor's elements into the model's totals before it is read, so a model
    /// whose primitives share one huge accessor is refused before anything is allocated.
    void reserve_elements(int accessor, std::uint64_t& total, std::uint64_t limit,
                          const char* unit) {
        if (accessor < 0 || static_cast<std::size_t>(accessor) >= gltf_.accessors.size()) return;
        total += gltf_.accessors[static_cast<std::size_t>(accessor)].count;
        stereoscene::support::check_limit("the model's " + std::string(unit), total, limit, unit,
                                          stereoscene::support::kVerticesHint);
    }

    void add_mesh(int mesh_index, const glm::mat4& world) {
        const tinygltf::Mesh& mesh = gltf_.meshes[static_cast<std::size_t>(mesh_index)];
        for (std::size_t p = 0; p < mesh.primitives.size(); ++p) {
            const tinygltf::Primitive& prim = mesh.primitives[p];
            const std::string what = "mesh " + std::to_string(mesh_index) + " (" + mesh.name +
                                     ") primitive " + std::to_string(p);
            if (prim.mode != TINYGLTF_MODE_TRIANGLES && prim.mode != -1) {
                out_.warnings.push_back(what + ": mode " + mode_name(prim.mode) +
                                        " skipped, only TRIANGLES are drawn");
                continue;
            }
            out_.primitives.push_back(convert_primitive(prim, world, what));
        }
    }

    MeshPrimitive convert_primitive(const tinygltf::Primitive& prim, const glm::mat4& world,
                                    const std::string& what) {
        MeshPrimitive out;
        const auto position = prim.attributes.find("POSITION");
        if (position == prim.attributes.end()) {
            throw LoadError(what + ": no POSITION attribute");
        }
        const std::uint64_t max_vertices = stereoscene::support::limits().max_model_vertices;
        for (const auto& [name, accessor] : prim.attributes) {
            if (name == "POSITION" || name == "NORMAL" || name == "TEXCOORD_0") {
                reserve_elements(accessor, vertices_, max_vertices, "vertices");
            }
        }
        reserve_elements(prim.indices, indices_, kIndicesPerVertex * max_vertices, "indices");
        out.positions = read_vectors<3>(gltf_, position->second, what + " POSITION");
        const std::size_t n = out.positions.size();
        const auto normal = prim.attributes.find("NORMAL");
        if (normal != prim.attributes.end()) {
            out.normals = read_vectors<3>(gltf_, normal->second, what + " NORMAL");
            if (out.normals.size() != n) throw LoadError(what + ": NORMAL count differs");
        }
        const auto uv = prim.attributes.find("TEXCOORD_0");
        if (uv != prim.attributes.end()) {
            out.texcoords = read_vectors<2>(gltf_, uv->second, what + " TEXCOORD_0");
            if (out.texcoords.size() != n) throw LoadError(what + ": TEXCOORD_0 count differs");
        }
        if (prim.indices >= 0) {
            out.indices = read_indices(gltf_, prim.indices, what + " indices");
        } else {
            if (n > std::numeric_limits<std::uint32_t>::max()) {
                throw LoadError(what + ": too many vertices");
            }
            out.indices.resize(n);
            for (std::size_t i = 0; i < n; ++i) out.indices[i] = static_cast<std::uint32_t>(i);
        }
        if (out.indices.size() % 3 != 0) {
            throw LoadError(what + ": index count " + std::to_string(out.indices.size()) +
                            " is not a multiple of 3");
        }
        for (std::uint32_t i : out.indices) {
            if (i >= n) {
                throw LoadError(what + ": index " + std::to_string(i) + " out of range (" +
                                std::to_string(n) + " vertices)");
            }
        }
        // Bake the node transform; a mirroring transform flips the winding back to CCW.
        const glm::mat3 normal_matrix = glm::transpose(glm::inverse(glm::mat3(world)));
        for (glm::vec3& v : out.positions) v = glm::vec3(world * glm::vec4(v, 1.0f));
        for (glm::vec3& v : out.normals) {
            const glm::vec3 t = normal_matrix * v;
            const float len = glm::length(t);
            v = len > 0.0f ? t / len : glm::vec3(0.0f, 1.0f, 0.0f);
        }
        if (glm::determinant(glm::mat3(world)) < 0.0f) {
            for (std::size_t t = 0; t + 2 < out.indices.size(); t += 3) {
                std::swap(out.indices[t + 1], out.indices[t + 2]);
            }
        }
        if (out.normals.empty()) compute_normals(out);
        apply_material(prim.material, out, what);
        return out;
    }

    void apply_material(int material_index, MeshPrimitive& out, const std::string& what) {
        if (material_index < 0) return;
        if (static_cast<std::size_t>(material_index) >= gltf_.materials.size()) {
            throw LoadError(what + ": material " + std::to_string(material_index) +
                            " does not exist");
        }
        const tinygltf::Material& material =
            gltf_.materials[static_cast<std::size_t>(material_index)];
        out.material_name = material.name;
        const tinygltf::PbrMetallicRoughness& pbr = material.pbrMetallicRoughness;
        out.material.metallic = static_cast<float>(pbr.metallicFactor);
        out.material.roughness = static_cast<float>(pbr.roughnessFactor);
        out.material.double_sided = material.doubleSided;
        out.material.alpha_mode = material.alphaMode.empty() ? "OPAQUE" : material.alphaMode;
        out.material.alpha_cutoff = static_cast<float>(material.alphaCutoff);
        if (material.emissiveFactor.size() == 3) {
            out.material.emissive = glm::vec3(
                material.emissiveFactor[0], material.emissiveFactor[1], material.emissiveFactor[2]);
        }
        if (pbr.baseColorFactor.size() == 4) {
            out.base_colour = glm::vec4(pbr.baseColorFactor[0], pbr.baseColorFactor[1],
                                        pbr.baseColorFactor[2], pbr.baseColorFactor[3]);
        }
        const int texture = pbr.baseColorTexture.index;
        if (texture < 0) return;
        if (static_cast<std::size_t>(texture) >= gltf_.textures.size()) {
            throw LoadError(what + ": texture " + std::to_string(texture) + " does not exist");
        }
        const tinygltf::Texture& gltf_texture = gltf_.textures[static_cast<std::size_t>(texture)];
        const int source = gltf_texture.source;
        if (source < 0 || static_cast<std::size_t>(source) >= gltf_.images.size()) {
            throw LoadError(what + ": texture " + std::to_string(texture) + " has no image");
        }
        const UvTransform uv_transform = texture_transform(pbr.baseColorTexture);
        if (uv_transform.tex_coord != 0) {
            out_.warnings.push_back(what + ": base colour texture uses TEXCOORD_" +
                                    std::to_string(uv_transform.tex_coord) +
                                    ", not loaded; drawn untextured");
            return;
        }
        int& slot = texture_slot_[static_cast<std::size_t>(source)];
        if (slot < 0) {
            const tinygltf::Image& image = gltf_.images[static_cast<std::size_t>(source)];
            if (image.image.empty() || image.component != 4 || image.bits != 8) {
                throw LoadError("image " + std::to_string(source) + " (" + image.uri +
                                ") could not be read");
            }
            ImageRgba8 decoded;
            decoded.width = image.width;
            decoded.height = image.height;
            decoded.pixels = image.image;
            slot = static_cast<int>(out_.textures.size());
            out_.textures.push_back(std::move(decoded));
        }
        out.texture = slot;
        if (gltf_texture.sampler >= 0 &&
            static_cast<std::size_t>(gltf_texture.sampler) < gltf_.samplers.size()) {
            const tinygltf::Sampler& s =
                gltf_.samplers[static_cast<std::size_t>(gltf_texture.sampler)];
            out.sampler = TextureSampler{s.magFilter, s.minFilter, s.wrapS, s.wrapT};
        }
        if (out.texcoords.empty()) {
            out_.warnings.push_back(what + ": textured material without TEXCOORD_0");
            out.texcoords.assign(out.positions.size(), glm::vec2(0.0f));
        }
        if (uv_transform.matrix != glm::mat3(1.0f)) {
            for (glm::vec2& uv : out.texcoords)
                uv = glm::vec2(uv_transform.matrix * glm::vec3(uv, 1));
        }
    }

    const tinygltf::Model& gltf_;
    Model& out_;
    std::vector<int> texture_slot_;  ///< glTF image index -> Model::textures index
    std::vector<bool> visited_;
    std::uint64_t vertices_ = 0;  ///< attribute elements counted so far, all primitives
    std::uint64_t indices_ = 0;   ///< indices counted so far, all primitives
};

Model convert_model(const tinygltf::Model& gltf, const fs::path& path) {
    Model model;
    model.name = path.filename().string();
    Converter(gltf, model).run();
    if (triangle_count(model) == 0) {
        throw LoadError("no triangles in the default scene");
    }
    update_bounds(model);
    return model;
}

}  // namespace

Model load_model(const std::filesystem::path& path) {
    try {
        return convert_model(read_gltf(path), path);
    } catch (const std::bad_alloc&) {
        throw std::runtime_error(path.string() + ": out of memory loading the model");
    } catch (const std::exception& e) {
        throw std::runtime_error(path.string() + ": " + e.what());
    }
}

Model load_model_memory(const std::vector<unsigned char>& bytes,
                        const std::filesystem::path& path) {
    try {
        return convert_model(read_gltf_memory(bytes, path), path);
    } catch (const std::exception& e) {
        throw std::runtime_error(path.string() + ": " + e.what());
    }
}

std::size_t triangle_count(const Model& model) {
    std::size_t count = 0;
    for (const MeshPrimitive& p : model.primitives) count += p.indices.size() / 3;
    return count;
}

void update_bounds(Model& model) {
    glm::vec3 lo(std::numeric_limits<float>::max());
    glm::vec3 hi(std::numeric_limits<float>::lowest());
    bool any = false;
    for (const MeshPrimitive& p : model.primitives) {
        for (const glm::vec3& v : p.positions) {
            const glm::vec3 w(p.node_transform * glm::vec4(v, 1.0f));
            lo = glm::min(lo, w);
            hi = glm::max(hi, w);
            any = true;
        }
    }
    if (!any) {
        throw std::invalid_argument("update_bounds: model " + model.name + " has no vertex");
    }
    model.bounds_min = lo;
    model.bounds_max = hi;
}

void compute_normals(MeshPrimitive& primitive) {
    std::vector<glm::vec3> sum(primitive.positions.size(), glm::vec3(0.0f));
    for (std::size_t t = 0; t + 2 < primitive.indices.size(); t += 3) {
        const std::uint32_t a = primitive.indices[t];
        const std::uint32_t b = primitive.indices[t + 1];
        const std::uint32_t c = primitive.indices[t + 2];
        // The cross product's length is twice the area: larger triangles weigh more.
        const glm::vec3 n = glm::cross(primitive.positions[b] - primitive.positions[a],
                                       primitive.positions[c] - primitive.positions[a]);
        sum[a] += n;
        sum[b] += n;
        sum[c] += n;
    }
    for (glm::vec3& n : sum) {
        const float len = glm::length(n);
        n = len > 0.0f ? n / len : glm::vec3(0.0f, 1.0f, 0.0f);
    }
    primitive.normals = std::move(sum);
}

Model make_box_model(const glm::vec4& colour) {
    struct Face {
        glm::vec3 normal;
        glm::vec3 u;
        glm::vec3 v;
    };
    // u x v == normal, so each face's quad (-u-v, +u-v, +u+v, -u+v) is counter-clockwise.
    const std::array<Face, 6> faces = {{
        {{1, 0, 0}, {0, 0, -1}, {0, 1, 0}},
        {{-1, 0, 0}, {0, 0, 1}, {0, 1, 0}},
        {{0, 1, 0}, {1, 0, 0}, {0, 0, -1}},
        {{0, -1, 0}, {1, 0, 0}, {0, 0, 1}},
        {{0, 0, 1}, {1, 0, 0}, {0, 1, 0}},
        {{0, 0, -1}, {-1, 0, 0}, {0, 1, 0}},
    }};
    MeshPrimitive box;
    box.base_colour = colour;
    for (const Face& f : faces) {
        const auto base = static_cast<std::uint32_t>(box.positions.size());
        const glm::vec3 c = 0.5f * f.normal;
        const std::array<glm::vec2, 4> corners = {{{-1, -1}, {1, -1}, {1, 1}, {-1, 1}}};
        for (const glm::vec2& k : corners) {
            box.positions.push_back(c + 0.5f * k.x * f.u + 0.5f * k.y * f.v);
            box.normals.push_back(f.normal);
        }
        for (std::uint32_t i : {0u, 1u, 2u, 0u, 2u, 3u}) box.indices.push_back(base + i);
    }
    Model model;
    model.name = "box";
    model.primitives.push_back(std::move(box));
    update_bounds(model);
    return model;
}

}  // namespace scene_viewer
