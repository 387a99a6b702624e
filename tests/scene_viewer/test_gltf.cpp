#include <catch2/catch.hpp>

#include <filesystem>
#include <fstream>
#include <string>

#include <unistd.h>

#include <scene_viewer/assets/gltf_loader.hpp>
#include <stereoscene/support/limits.hpp>

namespace fs = std::filesystem;
using scene_viewer::load_model;
using scene_viewer::Model;

namespace {

const fs::path kGltfDir = fs::path(STEREOSCENE_SOURCE_DIR) / "tests/scene_viewer/data/gltf";

std::string load_error(const fs::path& path) {
    try {
        load_model(path);
    } catch (const std::runtime_error& e) {
        return e.what();
    }
    return "";
}

void require_vec3(const glm::vec3& got, const glm::vec3& want) {
    CHECK(got.x == Approx(want.x).margin(1e-6));
    CHECK(got.y == Approx(want.y).margin(1e-6));
    CHECK(got.z == Approx(want.z).margin(1e-6));
}

/// A fresh empty folder under the system's temp directory.
fs::path temp_folder(const std::string& name) {
    const fs::path dir = fs::temp_directory_path() /
                         ("stereoscene-test-gltf-" + name + "-" + std::to_string(::getpid()));
    fs::remove_all(dir);
    fs::create_directories(dir);
    return dir;
}

}  // namespace

TEST_CASE("a .glb with one triangle loads with its bounds, normals and colour", "[gltf]") {
    const Model model = load_model(kGltfDir / "triangle.glb");
    CHECK(model.name == "triangle.glb");
    REQUIRE(model.primitives.size() == 1);
    const auto& p = model.primitives[0];
    CHECK(p.indices == std::vector<std::uint32_t>{0, 1, 2});
    REQUIRE(p.normals.size() == 3);
    require_vec3(p.normals[0], {0, 0, 1});
    CHECK(p.base_colour == glm::vec4(1, 0, 0, 1));
    CHECK(p.texture == -1);
    require_vec3(model.bounds_min, {0, 0, 0});
    require_vec3(model.bounds_max, {1, 1, 0});
    CHECK(model.warnings.empty());
}

TEST_CASE("a .gltf with an external .bin loads and its missing normals are computed", "[gltf]") {
    const Model model = load_model(kGltfDir / "quad_external.gltf");
    REQUIRE(model.primitives.size() == 1);
    const auto& p = model.primitives[0];
    CHECK(scene_viewer::triangle_count(model) == 2);
    REQUIRE(p.normals.size() == 4);
    for (const glm::vec3& n : p.normals) require_vec3(n, {0, 0, 1});
    CHECK(p.base_colour == glm::vec4(1.0f));  // no material: glTF's default white
    require_vec3(model.bounds_min, {-1, -1, 0});
    require_vec3(model.bounds_max, {1, 1, 0});
}

TEST_CASE("a .gltf with a data: URI and no indices gets sequential indices", "[gltf]") {
    const Model model = load_model(kGltfDir / "quad_datauri.gltf");
    REQUIRE(model.primitives.size() == 1);
    const auto& p = model.primitives[0];
    CHECK(p.positions.size() == 6);
    CHECK(p.indices == std::vector<std::uint32_t>{0, 1, 2, 3, 4, 5});
    REQUIRE(p.normals.size() == 6);
    require_vec3(p.normals[5], {0, 0, 1});
}

TEST_CASE("node hierarchy transforms are baked into positions", "[gltf]") {
    // parent: translate (10,0,0); child: translate (0,5,0), scale 2; triangle (0,0,0) (1,0,0)
    // (0,1,0) -> (10,5,0) (12,5,0) (10,7,0).
    const Model model = load_model(kGltfDir / "hierarchy.gltf");
    REQUIRE(model.primitives.size() == 1);
    const auto& p = model.primitives[0];
    CHECK(p.node_transform == glm::mat4(1.0f));
    require_vec3(p.positions[0], {10, 5, 0});
    require_vec3(p.positions[1], {12, 5, 0});
    require_vec3(p.positions[2], {10, 7, 0});
    require_vec3(model.bounds_min, {10, 5, 0});
    require_vec3(model.bounds_max, {12, 7, 0});
}

TEST_CASE("a mirroring node transform keeps triangles counter-clockwise from the front", "[gltf]") {
    // The +z-facing triangle mirrored in x still faces +z; its winding must be flipped back.
    const Model model = load_model(kGltfDir / "mirrored.gltf");
    REQUIRE(model.primitives.size() == 1);
    const auto& p = model.primitives[0];
    const glm::vec3 a = p.positions[p.indices[0]];
    const glm::vec3 b = p.positions[p.indices[1]];
    const glm::vec3 c = p.positions[p.indices[2]];
    require_vec3(glm::normalize(glm::cross(b - a, c - a)), {0, 0, 1});
    require_vec3(p.normals[0], {0, 0, 1});
    require_vec3(model.bounds_min, {-1, 0, 0});
}

TEST_CASE("two primitives of one mesh keep their own materials", "[gltf]") {
    const Model model = load_model(kGltfDir / "two_primitives.gltf");
    REQUIRE(model.primitives.size() == 2);
    CHECK(model.primitives[0].base_colour == glm::vec4(1, 0, 0, 1));
    CHECK(model.primitives[1].base_colour == glm::vec4(0, 0, 1, 1));
    CHECK(model.primitives[0].indices.size() == 3);
    CHECK(model.primitives[1].indices.size() == 6);  // unsigned byte indices
    require_vec3(model.bounds_min, {-1, -1, 0});
    require_vec3(model.bounds_max, {1, 1, 1});
}

TEST_CASE("a base colour texture is decoded to RGBA8 with its texture coordinates", "[gltf]") {
    const Model model = load_model(kGltfDir / "textured.gltf");
    REQUIRE(model.textures.size() == 1);
    const auto& image = model.textures[0];
    REQUIRE(image.width == 2);
    REQUIRE(image.height == 2);
    REQUIRE(image.pixels.size() == 16);
    // Rows top to bottom: red, green / blue, white.
    CHECK(std::vector<std::uint8_t>(image.pixels.begin(), image.pixels.begin() + 4) ==
          std::vector<std::uint8_t>{255, 0, 0, 255});
    CHECK(std::vector<std::uint8_t>(image.pixels.begin() + 8, image.pixels.begin() + 12) ==
          std::vector<std::uint8_t>{0, 0, 255, 255});
    REQUIRE(model.primitives.size() == 1);
    const auto& p = model.primitives[0];
    CHECK(p.texture == 0);
    REQUIRE(p.texcoords.size() == 4);
    CHECK(p.texcoords[0] == glm::vec2(0, 1));
    CHECK(p.texcoords[2] == glm::vec2(1, 0));
}

TEST_CASE("KHR_texture_transform is applied to the texture coordinates", "[gltf]") {
    // Specification matrix T(offset) R(rotation) S(scale): uv (1, 0) -> scale (0.5, 0) ->
    // rotate 90 degrees (0, 0.5) -> offset (0.5, 0.75); uv (0, 1) -> (0, 2) -> (-2, 0) ->
    // (-1.5, 0.25).
    const Model model = load_model(kGltfDir / "textured_transform.gltf");
    REQUIRE(model.primitives.size() == 1);
    const auto& uv = model.primitives[0].texcoords;
    REQUIRE(uv.size() == 4);
    CHECK(uv[2].x == Approx(0.5f).margin(1e-6));  // QUAD_UV[2] = (1, 0)
    CHECK(uv[2].y == Approx(0.75f).margin(1e-6));
    CHECK(uv[0].x == Approx(-1.5f).margin(1e-6));  // QUAD_UV[0] = (0, 1)
    CHECK(uv[0].y == Approx(0.25f).margin(1e-6));
    CHECK(model.primitives[0].texture == 0);
}

TEST_CASE("a LINES primitive is skipped with a warning and the triangles still load", "[gltf]") {
    const Model model = load_model(kGltfDir / "lines_and_triangles.gltf");
    REQUIRE(model.primitives.size() == 1);
    REQUIRE(model.warnings.size() == 1);
    CHECK_THAT(model.warnings[0], Catch::Contains("LINES"));
    require_vec3(model.bounds_max, {1, 1, 0});  // the line's (5,5,5) is not part of the model
}

TEST_CASE("URIs that leave the model's folder are refused before anything is read", "[gltf]") {
    for (const char* name : {"escape_parent.gltf", "escape_encoded.gltf", "escape_absolute.gltf",
                             "escape_file_uri.gltf"}) {
        INFO(name);
        const std::string error = load_error(kGltfDir / name);
        CHECK_THAT(error, Catch::StartsWith((kGltfDir / name).string() + ": "));
        CHECK_THAT(error, Catch::Contains("/buffers/0/uri") && Catch::Contains("refused"));
    }
    CHECK_THAT(load_error(kGltfDir / "escape_parent.gltf"), Catch::Contains("leaves"));
    CHECK_THAT(load_error(kGltfDir / "escape_absolute.gltf"), Catch::Contains("absolute"));
}

TEST_CASE("a symbolic link that points out of the model's folder is refused", "[gltf]") {
    const fs::path dir = temp_folder("symlink");
    fs::copy_file(kGltfDir / "quad_external.gltf", dir / "quad_external.gltf");
    fs::create_symlink(kGltfDir / "quad_external.bin", dir / "quad_external.bin");
    const std::string error = load_error(dir / "quad_external.gltf");
    CHECK_THAT(error, Catch::StartsWith((dir / "quad_external.gltf").string() + ": "));
    CHECK_THAT(error, Catch::Contains("outside the model's folder"));
    // The same file beside a real copy of the buffer loads.
    fs::remove(dir / "quad_external.bin");
    fs::copy_file(kGltfDir / "quad_external.bin", dir / "quad_external.bin");
    CHECK(scene_viewer::triangle_count(load_model(dir / "quad_external.gltf")) == 2);
    fs::remove_all(dir);
}

TEST_CASE("a truncated .glb is refused and the error names the file", "[gltf]") {
    const std::string error = load_error(kGltfDir / "truncated.glb");
    CHECK_THAT(error, Catch::StartsWith((kGltfDir / "truncated.glb").string() + ": "));
    CHECK_THAT(error, Catch::Contains("truncated .glb"));
}

TEST_CASE("a missing file and a file that is not glTF are refused with the file name", "[gltf]") {
    CHECK_THAT(load_error(kGltfDir / "no_such_model.glb"),
               Catch::StartsWith((kGltfDir / "no_such_model.glb").string() +
                                 ": cannot open: No such file"));
    CHECK_THAT(load_error(kGltfDir / "checker.png"),
               Catch::StartsWith((kGltfDir / "checker.png").string() + ": not valid glTF JSON: "));
}

TEST_CASE("a buffer shorter than its accessors is refused", "[gltf]") {
    const fs::path dir = temp_folder("short-buffer");
    fs::copy_file(kGltfDir / "quad_external.gltf", dir / "quad_external.gltf");
    std::ofstream(dir / "quad_external.bin", std::ios::binary) << std::string(20, '\0');
    const std::string error = load_error(dir / "quad_external.gltf");
    CHECK_THAT(error, Catch::StartsWith((dir / "quad_external.gltf").string() + ": "));
    CHECK_FALSE(error.empty());
    fs::remove_all(dir);
}

TEST_CASE("an accessor with an absurd element count is refused before allocating", "[gltf]") {
    const fs::path dir = temp_folder("huge-accessor");
    std::ofstream(dir / "huge.gltf") << R"({"asset": {"version": "2.0"},
        "accessors": [{"count": 100000000, "type": "VEC3", "componentType": 5126}],
        "meshes": [{"primitives": [{"attributes": {"POSITION": 0}}]}],
        "nodes": [{"mesh": 0}], "scenes": [{"nodes": [0]}], "scene": 0})";
    const std::string error = load_error(dir / "huge.gltf");
    CHECK_THAT(error, Catch::StartsWith((dir / "huge.gltf").string() + ": "));
    CHECK_THAT(error, Catch::Contains("100000000 vertices is more than the limit"));
    fs::remove_all(dir);
}

TEST_CASE("computed normals are the area-weighted average of the adjacent faces", "[gltf]") {
    // Two faces share the edge (0,0,0)-(1,0,0): one in the z = 0 plane (area 1, normal +z),
    // one in the y = 0 plane (area 0.5, normal -y).
    scene_viewer::MeshPrimitive p;
    p.positions = {{0, 0, 0}, {1, 0, 0}, {0, 2, 0}, {0, 0, 1}};
    p.indices = {0, 1, 2, 0, 1, 3};
    scene_viewer::compute_normals(p);
    REQUIRE(p.normals.size() == 4);
    require_vec3(p.normals[2], {0, 0, 1});
    require_vec3(p.normals[3], {0, -1, 0});
    // Shared vertices: face areas 1 (+z) and 0.5 (-y) -> direction (0, -0.5, 1) normalised.
    const glm::vec3 expected = glm::normalize(glm::vec3(0, -0.5f, 1));
    require_vec3(p.normals[0], expected);
    require_vec3(p.normals[1], expected);
}

namespace {

/// A one-triangle glTF document (its buffer as a data: URI) with `extra` JSON members spliced
/// into the top level, e.g. nodes, meshes and scenes.
std::string triangle_gltf(const std::string& buffer_views, const std::string& extra) {
    // 3 float VEC3 positions (0,0,0) (1,0,0) (0,1,0), base64.
    const std::string data = "AAAAAAAAAAAAAAAAAACAPwAAAAAAAAAAAAAAAAAAgD8AAAAA";
    return R"({"asset": {"version": "2.0"},
        "buffers": [{"byteLength": 36, "uri": "data:application/octet-stream;base64,)" +
           data + R"("}], "bufferViews": )" + buffer_views + R"(,
        "accessors": [{"bufferView": 0, "componentType": 5126, "count": 3, "type": "VEC3"}],)" +
           extra + "}";
}

}  // namespace

TEST_CASE("buffer view offsets that would wrap 64-bit sums are refused before tinygltf", "[gltf]") {
    const fs::path dir = temp_folder("wrap");
    std::ofstream(dir / "wrap.gltf")
        << triangle_gltf(R"([{"buffer": 0, "byteOffset": 18446744073709551600, "byteLength": 36}])",
                         R"("meshes": [{"primitives": [{"attributes": {"POSITION": 0}}]}],
           "nodes": [{"mesh": 0}], "scenes": [{"nodes": [0]}])");
    CHECK_THAT(load_error(dir / "wrap.gltf"),
               Catch::Contains("/bufferViews/0/byteOffset: 18446744073709551600 too large"));
    std::ofstream(dir / "image.gltf") << triangle_gltf(
        R"([{"buffer": 0, "byteLength": 36}, {"buffer": 0, "byteOffset": 30, "byteLength": 99}])",
        R"("images": [{"bufferView": 1, "mimeType": "image/png"}],
           "meshes": [{"primitives": [{"attributes": {"POSITION": 0}}]}],
           "nodes": [{"mesh": 0}], "scenes": [{"nodes": [0]}])");
    CHECK_THAT(load_error(dir / "image.gltf"),
               Catch::Contains("/bufferViews/1: byteOffset + byteLength 129 runs past"));
    fs::remove_all(dir);
}

TEST_CASE("a chain of 200,000 nodes loads without recursion", "[gltf]") {
    const fs::path dir = temp_folder("chain");
    std::string nodes = "[";
    constexpr int kNodes = 200000;
    for (int i = 0; i + 1 < kNodes; ++i)
        nodes += R"({"children": [)" + std::to_string(i + 1) + "]},";
    nodes += R"({"mesh": 0}])";
    std::ofstream(dir / "chain.gltf")
        << triangle_gltf(R"([{"buffer": 0, "byteLength": 36}])",
                         R"("meshes": [{"primitives": [{"attributes": {"POSITION": 0}}]}],
           "scenes": [{"nodes": [0]}], "nodes": )" +
                             nodes);
    const scene_viewer::Model model = scene_viewer::load_model(dir / "chain.gltf");
    CHECK(scene_viewer::triangle_count(model) == 1);
    fs::remove_all(dir);
}

TEST_CASE("primitives that share an accessor count against the model's vertex limit", "[gltf]") {
    const fs::path dir = temp_folder("shared");
    std::ofstream(dir / "shared.gltf")
        << triangle_gltf(R"([{"buffer": 0, "byteLength": 36}])",
                         R"("meshes": [{"primitives": [{"attributes": {"POSITION": 0}},
                                      {"attributes": {"POSITION": 0}},
                                      {"attributes": {"POSITION": 0}}]}],
           "nodes": [{"mesh": 0}], "scenes": [{"nodes": [0]}])");
    const stereoscene::support::Limits saved = stereoscene::support::limits();
    stereoscene::support::Limits small = saved;
    small.max_model_vertices = 8;  // two primitives of 3 fit, the third does not
    stereoscene::support::set_limits(small);
    const std::string error = load_error(dir / "shared.gltf");
    stereoscene::support::set_limits(saved);
    CHECK_THAT(error, Catch::Contains("9 vertices is more than the limit of 8"));
    CHECK(scene_viewer::triangle_count(scene_viewer::load_model(dir / "shared.gltf")) == 3);
    fs::remove_all(dir);
}
