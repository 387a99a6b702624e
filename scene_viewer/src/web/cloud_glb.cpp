// The point cloud as binary glTF POINTS meshes, one per class, for the browser viewer.
#include <algorithm>
#include <cmath>
#include <limits>
#include <map>
#include <random>
#include <sstream>
#include <stdexcept>

#include <tiny_gltf.h>

#include "../assets/gltf_internal.hpp"
#include "scene_viewer/assets/palette.hpp"
#include "scene_viewer/ecs/coordinates.hpp"
#include "scene_viewer/web/viewer_folder.hpp"

namespace scene_viewer {
namespace {

constexpr int kArrayBuffer = 34962;  // GL_ARRAY_BUFFER
constexpr int kNoClass = std::numeric_limits<int>::min();

/// sRGB byte -> linear byte (glTF vertex colours are linear).
std::uint8_t linear_byte(std::uint8_t srgb) {
    const double c = srgb / 255.0;
    const double linear = c <= 0.04045 ? c / 12.92 : std::pow((c + 0.055) / 1.055, 2.4);
    return static_cast<std::uint8_t>(std::lround(linear * 255.0));
}

int add_accessor(tinygltf::Model& gltf, const void* data, std::size_t count, std::size_t stride,
                 int type, int component_type, bool normalized) {
    tinygltf::Accessor accessor;
    accessor.bufferView = gltf_detail::append_buffer_view(gltf, data, count * stride, kArrayBuffer);
    accessor.componentType = component_type;
    accessor.count = count;
    accessor.type = type;
    accessor.normalized = normalized;
    gltf.accessors.push_back(std::move(accessor));
    return static_cast<int>(gltf.accessors.size()) - 1;
}

/// One POINTS mesh and its node for the points of `indices`.
void add_class(tinygltf::Model& gltf, const PointCloud& cloud, int class_id,
               const std::vector<std::size_t>& indices) {
    std::vector<glm::vec3> positions;
    positions.reserve(indices.size());
    glm::vec3 lo(std::numeric_limits<float>::max()), hi(std::numeric_limits<float>::lowest());
    for (std::size_t i : indices) {
        const glm::vec3 p = kitti_to_gl(cloud.positions_kitti[i]);
        positions.push_back(p);
        lo = glm::min(lo, p);
        hi = glm::max(hi, p);
    }
    tinygltf::Primitive primitive;
    primitive.mode = TINYGLTF_MODE_POINTS;
    const int pos = add_accessor(gltf, positions.data(), positions.size(), sizeof(glm::vec3),
                                 TINYGLTF_TYPE_VEC3, TINYGLTF_COMPONENT_TYPE_FLOAT, false);
    gltf.accessors[static_cast<std::size_t>(pos)].minValues = {lo.x, lo.y, lo.z};
    gltf.accessors[static_cast<std::size_t>(pos)].maxValues = {hi.x, hi.y, hi.z};
    primitive.attributes["POSITION"] = pos;
    if (!cloud.colours.empty()) {
        // Four bytes per colour: glTF aligns every vertex attribute element to 4 bytes.
        std::vector<std::uint8_t> rgba;
        rgba.reserve(indices.size() * 4);
        for (std::size_t i : indices) {
            for (int c = 0; c < 3; ++c) rgba.push_back(linear_byte(cloud.colours[i][c]));
            rgba.push_back(255);
        }
        primitive.attributes["COLOR_0"] =
            add_accessor(gltf, rgba.data(), indices.size(), 4, TINYGLTF_TYPE_VEC4,
                         TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE, true);
    }
    tinygltf::Material material;
    const Rgb8 colour = class_id == kNoClass ? Rgb8{90, 90, 90} : class_colour(class_id, "");
    material.name = class_id == kNoClass ? "cloud" : "cloud_class_" + std::to_string(class_id);
    const std::array<std::uint8_t, 3> base = cloud.colours.empty() ? colour : Rgb8{255, 255, 255};
    material.pbrMetallicRoughness.baseColorFactor = {linear_byte(base[0]) / 255.0,
                                                     linear_byte(base[1]) / 255.0,
                                                     linear_byte(base[2]) / 255.0, 1.0};
    material.extensions["KHR_materials_unlit"] = tinygltf::Value(tinygltf::Value::Object());
    gltf.materials.push_back(std::move(material));
    primitive.material = static_cast<int>(gltf.materials.size()) - 1;
    tinygltf::Mesh mesh;
    mesh.name = gltf.materials.back().name;
    mesh.primitives.push_back(std::move(primitive));
    gltf.meshes.push_back(std::move(mesh));
    tinygltf::Node node;
    node.name = gltf.meshes.back().name;
    node.mesh = static_cast<int>(gltf.meshes.size()) - 1;
    if (class_id != kNoClass) {
        tinygltf::Value::Object extras;
        extras["class_id"] = tinygltf::Value(class_id);
        node.extras = tinygltf::Value(extras);
    }
    gltf.nodes.push_back(std::move(node));
}

}  // namespace

std::vector<unsigned char> point_cloud_glb_bytes(const PointCloud& cloud) {
    if (!cloud.colours.empty() && cloud.colours.size() != cloud.size())
        throw std::invalid_argument("point_cloud_glb: colour count differs from point count");
    if (!cloud.class_ids.empty() && cloud.class_ids.size() != cloud.size())
        throw std::invalid_argument("point_cloud_glb: class count differs from point count");
    std::map<int, std::vector<std::size_t>> by_class;
    for (std::size_t i = 0; i < cloud.size(); ++i) {
        const glm::vec3& p = cloud.positions_kitti[i];
        if (!std::isfinite(p.x) || !std::isfinite(p.y) || !std::isfinite(p.z)) continue;
        by_class[cloud.class_ids.empty() ? kNoClass : cloud.class_ids[i]].push_back(i);
    }
    // A fixed-seed shuffle: every prefix of a class is a uniform sample of it.
    std::mt19937 random(20240607u);
    for (auto& [class_id, indices] : by_class) std::shuffle(indices.begin(), indices.end(), random);
    tinygltf::Model gltf;
    gltf.asset.version = "2.0";
    gltf.asset.generator = "stereoscene scene-render";
    gltf.extensionsUsed.push_back("KHR_materials_unlit");
    gltf.buffers.emplace_back();
    for (const auto& [class_id, indices] : by_class) add_class(gltf, cloud, class_id, indices);
    tinygltf::Scene scene;
    scene.name = "cloud";
    for (std::size_t i = 0; i < gltf.nodes.size(); ++i) scene.nodes.push_back(static_cast<int>(i));
    gltf.scenes.push_back(std::move(scene));
    gltf.defaultScene = 0;
    if (gltf.buffers[0].data.empty()) gltf.buffers.clear();
    tinygltf::TinyGLTF writer;
    std::ostringstream out;
    if (!writer.WriteGltfSceneToStream(&gltf, out, false, true))
        throw std::runtime_error("point_cloud_glb: tinygltf could not serialise the cloud");
    const std::string bytes = out.str();
    return std::vector<unsigned char>(bytes.begin(), bytes.end());
}

}  // namespace scene_viewer
