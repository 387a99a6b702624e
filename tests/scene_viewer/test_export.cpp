#include <catch2/catch.hpp>

#include <cstdint>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>

#include <unistd.h>

#include <glm/gtc/matrix_transform.hpp>
#include <nlohmann/json.hpp>
#include <scene_viewer/assets/gltf_loader.hpp>
#include <scene_viewer/assets/scene_export.hpp>

namespace fs = std::filesystem;
using scene_viewer::load_model;
using scene_viewer::Model;
using scene_viewer::PlacedModel;

namespace {

const fs::path kModelsDir = fs::path(STEREOSCENE_SOURCE_DIR) / "assets/models";
const fs::path kGltfDir = fs::path(STEREOSCENE_SOURCE_DIR) / "tests/scene_viewer/data/gltf";

fs::path temp_folder(const std::string& name) {
    const fs::path dir = fs::temp_directory_path() /
                         ("stereoscene-test-export-" + name + "-" + std::to_string(::getpid()));
    fs::remove_all(dir);
    fs::create_directories(dir);
    return dir;
}

void check_vec3(const glm::vec3& got, const glm::vec3& want) {
    CHECK(got.x == Approx(want.x).margin(1e-4));
    CHECK(got.y == Approx(want.y).margin(1e-4));
    CHECK(got.z == Approx(want.z).margin(1e-4));
}

}  // namespace

TEST_CASE("an exported scene loads back with the same triangles and world bounds", "[export]") {
    const Model car = load_model(kModelsDir / "car.glb");
    const Model tree = load_model(kModelsDir / "tree.glb");
    const glm::mat4 left = glm::translate(glm::mat4(1.0f), glm::vec3(-5.0f, 0.0f, 10.0f));
    // Turned a quarter about +y and scaled: the car's length now runs along x.
    const glm::mat4 right =
        glm::scale(glm::rotate(glm::translate(glm::mat4(1.0f), glm::vec3(6.0f, 0.0f, 20.0f)),
                               glm::radians(90.0f), glm::vec3(0, 1, 0)),
                   glm::vec3(2.0f));
    const std::vector<PlacedModel> scene = {
        {&car, left, "car-left"}, {&car, right, "car-right"}, {&tree, glm::mat4(1.0f), "tree"}};
    const fs::path dir = temp_folder("roundtrip");
    const fs::path path = dir / "scene.glb";
    scene_viewer::export_scene_glb(scene, path);
    REQUIRE(fs::exists(path));
    const Model back = load_model(path);
    CHECK(scene_viewer::triangle_count(back) ==
          2 * scene_viewer::triangle_count(car) + scene_viewer::triangle_count(tree));
    glm::vec3 lo(1e9f);
    glm::vec3 hi(-1e9f);
    for (const PlacedModel& placed : scene) {
        for (const auto& p : placed.model->primitives) {
            for (const glm::vec3& v : p.positions) {
                const glm::vec3 w(placed.world * glm::vec4(v, 1.0f));
                lo = glm::min(lo, w);
                hi = glm::max(hi, w);
            }
        }
    }
    check_vec3(back.bounds_min, lo);
    check_vec3(back.bounds_max, hi);
    // Materials survive: the car body colour appears among the reloaded primitives.
    bool body_found = false;
    for (const auto& p : back.primitives) {
        body_found = body_found || p.base_colour == car.primitives[0].base_colour;
    }
    CHECK(body_found);
    CHECK(back.primitives[0].material_name == car.primitives[0].material_name);
    CHECK(car.primitives[0].material_name == "paint");
    // No temporary file is left beside the output.
    CHECK(std::distance(fs::directory_iterator(dir), fs::directory_iterator()) == 1);
    fs::remove_all(dir);
}

TEST_CASE("an exported textured model keeps its texture pixels", "[export]") {
    const Model textured = load_model(kGltfDir / "textured.gltf");
    const fs::path dir = temp_folder("texture");
    scene_viewer::export_scene_glb({{&textured, glm::mat4(1.0f), "quad"}}, dir / "tex.glb");
    const Model back = load_model(dir / "tex.glb");
    REQUIRE(back.textures.size() == 1);
    CHECK(back.textures[0].width == 2);
    CHECK(back.textures[0].pixels == textured.textures[0].pixels);
    REQUIRE(back.primitives.size() == 1);
    CHECK(back.primitives[0].texture == 0);
    CHECK(back.primitives[0].texcoords == textured.primitives[0].texcoords);
    fs::remove_all(dir);
}

/// The JSON chunk of a .glb file (12-byte header, then a JSON chunk: length, "JSON", text).
nlohmann::json glb_json(const fs::path& path) {
    std::ifstream in(path, std::ios::binary);
    std::ostringstream text;
    text << in.rdbuf();
    const std::string bytes = text.str();
    REQUIRE(bytes.size() > 20);
    REQUIRE(bytes.compare(0, 4, "glTF") == 0);
    std::uint32_t length = 0;
    std::memcpy(&length, bytes.data() + 12, 4);
    REQUIRE(bytes.compare(16, 4, "JSON") == 0);
    return nlohmann::json::parse(bytes.substr(20, length));
}

TEST_CASE("an exported third-party material keeps its sides, sampler and PBR factors", "[export]") {
    const Model kit = load_model(kGltfDir / "textured_material.gltf");
    REQUIRE(kit.primitives.size() == 1);
    CHECK(kit.primitives[0].material.double_sided);
    CHECK(kit.primitives[0].sampler.mag_filter == 9728);
    const fs::path dir = temp_folder("material");
    scene_viewer::export_scene_glb({{&kit, glm::mat4(1.0f), "kit"}}, dir / "kit.glb");
    // Read by hand, not by our loader: what any viewer sees in the file.
    const nlohmann::json doc = glb_json(dir / "kit.glb");
    REQUIRE(doc["materials"].size() == 1);
    const auto& m = doc["materials"][0];
    CHECK(m["name"] == "kit");
    CHECK(m["doubleSided"] == true);
    CHECK(m["alphaMode"] == "MASK");
    CHECK(m["alphaCutoff"].get<double>() == Approx(0.4));
    CHECK(m["emissiveFactor"][0].get<double>() == Approx(0.25));
    CHECK(m["pbrMetallicRoughness"]["metallicFactor"].get<double>() == Approx(0.5));
    CHECK(m["pbrMetallicRoughness"]["roughnessFactor"].get<double>() == Approx(0.3));
    const int texture = m["pbrMetallicRoughness"]["baseColorTexture"]["index"];
    const int sampler = doc["textures"][texture]["sampler"];
    const auto& s = doc["samplers"][sampler];
    CHECK(s["magFilter"] == 9728);  // NEAREST
    CHECK(s["minFilter"] == 9728);
    CHECK(s["wrapS"] == 33071);  // CLAMP_TO_EDGE
    CHECK(s["wrapT"] == 33071);
    // And our own models keep their matte look, single-sided.
    const Model box = scene_viewer::make_box_model(glm::vec4(1.0f, 0.0f, 0.0f, 1.0f));
    scene_viewer::export_scene_glb({{&box, glm::mat4(1.0f), "box"}}, dir / "box.glb");
    const nlohmann::json box_doc = glb_json(dir / "box.glb");
    const auto& own = box_doc["materials"][0];
    CHECK((!own.contains("doubleSided") || own.at("doubleSided") == false));
    CHECK(own["pbrMetallicRoughness"]["roughnessFactor"].get<double>() == Approx(0.8));
    CHECK(own["pbrMetallicRoughness"]["metallicFactor"].get<double>() == Approx(0.0));
    fs::remove_all(dir);
}

TEST_CASE("a failed export throws and leaves no file", "[export]") {
    const Model box = scene_viewer::make_box_model(glm::vec4(1.0f));
    const fs::path dir = temp_folder("failure");
    CHECK_THROWS_WITH(
        scene_viewer::export_scene_glb({{nullptr, glm::mat4(1.0f), "x"}}, dir / "null.glb"),
        Catch::Contains("model is null"));
    glm::mat4 bad(1.0f);
    bad[3][0] = std::numeric_limits<float>::quiet_NaN();
    CHECK_THROWS_WITH(scene_viewer::export_scene_glb({{&box, bad, "nan"}}, dir / "nan.glb"),
                      Catch::Contains("not finite"));
    CHECK_THROWS(scene_viewer::export_scene_glb({{&box, glm::mat4(1.0f), "box"}},
                                                dir / "no_such_folder" / "box.glb"));
    CHECK(fs::is_empty(dir));
    fs::remove_all(dir);
}
