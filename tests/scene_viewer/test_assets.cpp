#include <catch2/catch.hpp>

#include <array>
#include <filesystem>
#include <fstream>
#include <map>
#include <set>
#include <string>

#include <unistd.h>

#include <nlohmann/json.hpp>

#include <scene_viewer/assets/class_table.hpp>
#include <scene_viewer/assets/gltf_loader.hpp>
#include <scene_viewer/assets/image_io.hpp>
#include <scene_viewer/assets/palette.hpp>
#include <scene_viewer/assets/vehicle_paints.hpp>

namespace fs = std::filesystem;
using scene_viewer::load_model;
using scene_viewer::Model;

namespace {

const fs::path kModelsDir = fs::path(STEREOSCENE_SOURCE_DIR) / "assets/models";
const fs::path kGltfDir = fs::path(STEREOSCENE_SOURCE_DIR) / "tests/scene_viewer/data/gltf";
const fs::path kThirdPartyDir = fs::path(STEREOSCENE_SHARED_DATA_DIR) / "../gltf-thirdparty";

/// Expected real-world size of each shipped model, metres: x (W), y (H), z (L) ranges.
struct SizeRange {
    glm::vec3 min;
    glm::vec3 max;
};

const std::map<std::string, SizeRange>& shipped_models() {
    static const std::map<std::string, SizeRange> models = {
        {"car.glb", {{1.6f, 1.2f, 3.6f}, {2.1f, 1.8f, 5.0f}}},
        {"truck.glb", {{2.2f, 2.8f, 6.0f}, {2.8f, 4.0f, 9.0f}}},
        {"bus.glb", {{2.3f, 2.8f, 10.0f}, {2.7f, 3.6f, 14.0f}}},
        {"person.glb", {{0.4f, 1.6f, 0.2f}, {0.9f, 1.9f, 0.5f}}},
        {"cyclist.glb", {{0.4f, 1.5f, 1.5f}, {0.9f, 2.0f, 2.0f}}},
        {"bicycle.glb", {{0.3f, 0.9f, 1.5f}, {0.8f, 1.2f, 2.0f}}},
        {"motorcycle.glb", {{0.5f, 0.9f, 1.8f}, {1.0f, 1.4f, 2.4f}}},
        {"tree.glb", {{2.5f, 4.0f, 2.5f}, {4.5f, 7.0f, 4.5f}}},
        {"hedge.glb", {{0.8f, 1.1f, 2.8f}, {1.3f, 1.4f, 3.3f}}},
        {"building.glb", {{5.0f, 5.0f, 5.0f}, {30.0f, 30.0f, 30.0f}}},
        {"pole.glb", {{0.1f, 4.0f, 0.1f}, {1.0f, 9.0f, 2.0f}}},
        {"traffic_sign.glb", {{0.3f, 2.0f, 0.02f}, {1.2f, 3.5f, 0.3f}}},
        {"traffic_light.glb", {{0.2f, 3.0f, 0.1f}, {0.8f, 4.5f, 0.5f}}},
    };
    return models;
}

std::string table_error(const fs::path& path) {
    try {
        scene_viewer::load_class_table(path);
    } catch (const std::runtime_error& e) {
        return e.what();
    }
    return "";
}

fs::path write_table(const std::string& name, const std::string& classes_json) {
    const fs::path dir =
        fs::temp_directory_path() / ("stereoscene-test-assets-" + std::to_string(::getpid()));
    fs::create_directories(dir);
    const fs::path path = dir / name;
    std::ofstream(path) << R"({"format": "stereoscene-render-classes", "version": 1, "classes": )"
                        << classes_json << "}\n";
    return path;
}

}  // namespace

TEST_CASE("every shipped model loads with realistic proportions within the triangle budget",
          "[assets]") {
    for (const auto& [file, size] : shipped_models()) {
        INFO(file);
        const Model model = load_model(kModelsDir / file);
        CHECK(model.warnings.empty());
        const std::size_t triangles = scene_viewer::triangle_count(model);
        CHECK(triangles >= 40);
        // The hedge is its leaves (scripts/make-models.py TRIANGLE_BUDGETS).
        CHECK(triangles <= (file == "hedge.glb" ? 2600u : 1500u));
        CHECK(model.primitives.size() >= 2);  // per-part materials, not one flat colour
        const glm::vec3 extent = model.bounds_max - model.bounds_min;
        CHECK(extent.x >= size.min.x);
        CHECK(extent.x <= size.max.x);
        CHECK(extent.y >= size.min.y);
        CHECK(extent.y <= size.max.y);
        CHECK(extent.z >= size.min.z);
        CHECK(extent.z <= size.max.z);
        CHECK(model.bounds_min.y == Approx(0.0f).margin(1e-4));  // standing on y = 0
        for (const auto& p : model.primitives) {
            REQUIRE(p.normals.size() == p.positions.size());
            for (const glm::vec3& n : p.normals) CHECK(glm::length(n) == Approx(1.0f));
        }
    }
}

TEST_CASE("the shipped car faces +z: headlights at the front, tail lights at the back",
          "[assets]") {
    const Model car = load_model(kModelsDir / "car.glb");
    // Materials are told apart by their base colour: the headlights are the near-white parts.
    float headlight_z = 0.0f;
    float taillight_z = 0.0f;
    for (const auto& p : car.primitives) {
        if (p.base_colour.r > 0.9f && p.base_colour.g > 0.9f) headlight_z = p.positions[0].z;
        if (p.base_colour.r > 0.5f && p.base_colour.g < 0.1f) taillight_z = p.positions[0].z;
    }
    CHECK(headlight_z > 2.0f);
    CHECK(taillight_z < -2.0f);
}

namespace {

/// The bundled Cityscapes palette, the one source of class names, ids and colours.
struct PaletteClass {
    int id;
    std::array<std::uint8_t, 3> colour;
};
std::map<std::string, PaletteClass> cityscapes_palette() {
    std::ifstream in(fs::path(STEREOSCENE_SOURCE_DIR) / "assets" / "palettes" / "cityscapes.json");
    const nlohmann::json j = nlohmann::json::parse(in);
    std::map<std::string, PaletteClass> out;
    for (const auto& c : j.at("classes")) {
        out[c.at("name").get<std::string>()] =
            PaletteClass{c.at("id").get<int>(), c.at("colour").get<std::array<std::uint8_t, 3>>()};
    }
    return out;
}

}  // namespace

TEST_CASE("the class table and the renderer's palette agree with the palette file", "[assets]") {
    const auto palette = cityscapes_palette();
    REQUIRE(palette.size() > 20);
    const scene_viewer::ClassTable table =
        scene_viewer::load_class_table(scene_viewer::default_class_table_path());
    for (const scene_viewer::RenderClass& c : table.classes) {
        INFO(c.name);
        REQUIRE(palette.count(c.name) == 1);
        CHECK(c.class_id == palette.at(c.name).id);
        CHECK(c.colour_srgb == palette.at(c.name).colour);
    }
    int known = 0;
    for (int id = 0; id < 256; ++id) {
        const auto entry = scene_viewer::cityscapes_by_id(id);
        if (!entry) continue;
        ++known;
        INFO(entry->name);
        REQUIRE(palette.count(entry->name) == 1);
        CHECK(palette.at(entry->name).id == id);
        CHECK(entry->colour == palette.at(entry->name).colour);
        CHECK(scene_viewer::cityscapes_by_name(entry->name)->class_id == id);
    }
    CHECK(known == 22);
    for (const auto& [name, c] : palette) {
        const auto entry = scene_viewer::cityscapes_by_name(name);
        if (entry) CHECK(entry->class_id == c.id);
    }
}

TEST_CASE("the class table maps every class to its labelId, palette colour and model", "[assets]") {
    const scene_viewer::ClassTable table =
        scene_viewer::load_class_table(scene_viewer::default_class_table_path());
    const auto palette = cityscapes_palette();
    struct Expected {
        const char* name;
        scene_viewer::RenderKind kind;
    };
    using K = scene_viewer::RenderKind;
    const Expected expected[] = {
        {"road", K::Ground},       {"sidewalk", K::Ground},      {"static", K::Block},
        {"building", K::Block},    {"wall", K::Block},           {"fence", K::Block},
        {"pole", K::Object},       {"traffic light", K::Object}, {"traffic sign", K::Object},
        {"vegetation", K::Object}, {"terrain", K::Ground},       {"person", K::Object},
        {"rider", K::Object},      {"car", K::Object},           {"truck", K::Object},
        {"bus", K::Object},        {"train", K::Object},         {"motorcycle", K::Object},
        {"bicycle", K::Object},
    };
    CHECK(table.classes.size() == std::size(expected));
    for (const Expected& e : expected) {
        INFO(e.name);
        const scene_viewer::RenderClass* row = table.find(std::string_view(e.name));
        REQUIRE(row != nullptr);
        CHECK(table.find(palette.at(e.name).id) == row);
        CHECK(row->colour_srgb == palette.at(e.name).colour);
        CHECK(row->kind == e.kind);
    }
    for (const char* name : {"car", "truck", "bus", "person", "rider", "bicycle", "motorcycle",
                             "vegetation", "building", "pole", "traffic sign", "traffic light"}) {
        INFO(name);
        const scene_viewer::RenderClass* row = table.find(std::string_view(name));
        REQUIRE(row != nullptr);
        REQUIRE_FALSE(row->model.empty());
        CHECK(scene_viewer::triangle_count(load_model(row->model)) > 0);
    }
    CHECK(table.find(std::string_view("train"))->model.empty());
    // Vegetation lower than it is long is a hedge or a bush, not a tree.
    CHECK(table.find(std::string_view("vegetation"))->low_model.filename() == "hedge.glb");
    CHECK(table.find(std::string_view("car"))->low_model.empty());
    CHECK(table.find(99) == nullptr);
}

TEST_CASE("class table errors name the file and the JSON pointer", "[assets]") {
    const fs::path bad_colour =
        write_table("bad_colour.json", R"([{"name": "car", "class_id": 26, "colour": [0, 0, 300],
                              "kind": "object"}])");
    CHECK(table_error(bad_colour) ==
          bad_colour.string() + ": /classes/0/colour/2: must be an integer 0..255");
    const fs::path bad_kind =
        write_table("bad_kind.json", R"([{"name": "car", "class_id": 26, "colour": [0, 0, 142],
                            "kind": "vehicle"}])");
    CHECK_THAT(table_error(bad_kind), Catch::Contains("/classes/0/kind: must be"));
    const fs::path duplicate =
        write_table("duplicate.json",
                    R"([{"name": "car", "class_id": 26, "colour": [0, 0, 142], "kind": "object"},
                             {"name": "auto", "class_id": 26, "colour": [0, 0, 142], "kind": "object"}])");
    CHECK_THAT(table_error(duplicate), Catch::Contains("/classes/1/class_id: duplicate"));
    const fs::path missing_model =
        write_table("missing_model.json", R"([{"name": "car", "class_id": 26, "colour": [0, 0, 142],
                                 "kind": "object", "model": "no_such_car.glb"}])");
    CHECK_THAT(table_error(missing_model),
               Catch::Contains("/classes/0/model: model file not found") &&
                   Catch::Contains("no_such_car.glb"));
    const std::string triangle = (kGltfDir / "triangle.glb").string();
    const fs::path missing_low = write_table(
        "missing_low.json", R"([{"name": "vegetation", "class_id": 21, "colour": [107, 142, 35],
                               "kind": "object", "model": ")" +
                                triangle + R"(", "low_model": "no_hedge.glb"}])");
    CHECK_THAT(table_error(missing_low),
               Catch::Contains("/classes/0/low_model: model file not found") &&
                   Catch::Contains("no_hedge.glb"));
    const fs::path lone_low = write_table(
        "lone_low.json", R"([{"name": "vegetation", "class_id": 21, "colour": [107, 142, 35],
                            "kind": "object", "low_model": ")" +
                             triangle + R"("}])");
    CHECK(table_error(lone_low) ==
          lone_low.string() + ": /classes/0/low_model: needs a model beside it");
    CHECK_THAT(table_error(kGltfDir / "checker.png"),
               Catch::Contains(": not valid JSON: parse error at line 1"));
    fs::remove_all(bad_colour.parent_path());
}

TEST_CASE("a user's class table resolves model paths against its own folder", "[assets]") {
    const fs::path dir = fs::temp_directory_path() /
                         ("stereoscene-test-assets-" + std::to_string(::getpid())) / "user";
    fs::create_directories(dir / "models");
    fs::copy_file(kGltfDir / "triangle.glb", dir / "models/my_car.glb",
                  fs::copy_options::overwrite_existing);
    const fs::path path = dir / "classes.json";
    std::ofstream(path) << R"({"format": "stereoscene-render-classes", "version": 1, "classes": [
        {"name": "car", "class_id": 26, "colour": [0, 0, 142], "kind": "object",
         "model": "models/my_car.glb"}]})";
    const scene_viewer::ClassTable table = scene_viewer::load_class_table(path);
    REQUIRE(table.classes.size() == 1);
    CHECK(table.classes[0].model == dir / "models/my_car.glb");
    CHECK(scene_viewer::triangle_count(load_model(table.classes[0].model)) == 1);
    fs::remove_all(dir.parent_path());
}

TEST_CASE("palette colours convert to linear base colours with the sRGB curve", "[assets]") {
    const glm::vec4 c = scene_viewer::linear_colour({0, 128, 255});
    CHECK(c.r == Approx(0.0f));
    CHECK(c.g == Approx(0.2158605f).epsilon(1e-4));
    CHECK(c.b == Approx(1.0f));
    CHECK(c.a == 1.0f);
}

TEST_CASE("the box model is a unit cube with outward normals and the given colour", "[assets]") {
    const Model box = scene_viewer::make_box_model({0.5f, 0.25f, 0.0f, 1.0f});
    REQUIRE(box.primitives.size() == 1);
    const auto& p = box.primitives[0];
    CHECK(scene_viewer::triangle_count(box) == 12);
    CHECK(p.base_colour == glm::vec4(0.5f, 0.25f, 0.0f, 1.0f));
    CHECK(box.bounds_min == glm::vec3(-0.5f));
    CHECK(box.bounds_max == glm::vec3(0.5f));
    for (std::size_t t = 0; t < p.indices.size(); t += 3) {
        const glm::vec3 a = p.positions[p.indices[t]];
        const glm::vec3 b = p.positions[p.indices[t + 1]];
        const glm::vec3 c = p.positions[p.indices[t + 2]];
        const glm::vec3 face = glm::normalize(glm::cross(b - a, c - a));
        const glm::vec3 centre = (a + b + c) / 3.0f;
        CHECK(glm::dot(face, centre) > 0.0f);  // counter-clockwise seen from outside
        CHECK(glm::dot(face, p.normals[p.indices[t]]) == Approx(1.0f));
    }
}

TEST_CASE("PNG encoding round-trips through decoding", "[assets]") {
    scene_viewer::ImageRgba8 image;
    image.width = 3;
    image.height = 2;
    for (int i = 0; i < 6; ++i) {
        image.pixels.insert(image.pixels.end(), {static_cast<std::uint8_t>(40 * i),
                                                 static_cast<std::uint8_t>(255 - 40 * i), 7,
                                                 static_cast<std::uint8_t>(i == 5 ? 0 : 255)});
    }
    const std::vector<unsigned char> png = scene_viewer::encode_png(image, 9);
    REQUIRE(png.size() > 8);
    CHECK(png[1] == 'P');
    const scene_viewer::ImageRgba8 back =
        scene_viewer::decode_image_memory(png.data(), png.size(), "memory");
    CHECK(back.width == 3);
    CHECK(back.height == 2);
    CHECK(back.pixels == image.pixels);
    image.pixels.pop_back();
    CHECK_THROWS_AS(scene_viewer::encode_png(image), std::invalid_argument);
    CHECK_THROWS_WITH(
        scene_viewer::decode_image(kGltfDir / "quad_external.bin"),
        Catch::StartsWith((kGltfDir / "quad_external.bin").string() + ": cannot decode image"));
}

TEST_CASE("third-party Kenney models (CC0) load with their external textures", "[assets][shared]") {
    REQUIRE(fs::is_directory(kThirdPartyDir));
    int loaded = 0;
    for (const auto& entry : fs::recursive_directory_iterator(kThirdPartyDir)) {
        if (entry.path().extension() != ".glb") continue;
        INFO(entry.path().string());
        const Model model = load_model(entry.path());
        CHECK(scene_viewer::triangle_count(model) > 0);
        REQUIRE(model.textures.size() == 1);  // every kit shares Textures/colormap.png
        CHECK(model.textures[0].width > 0);
        for (const auto& p : model.primitives) {
            CHECK(p.texture == 0);
            CHECK(p.texcoords.size() == p.positions.size());
        }
        const glm::vec3 extent = model.bounds_max - model.bounds_min;
        CHECK(extent.x > 0.0f);
        CHECK(extent.y > 0.0f);
        CHECK(extent.z > 0.0f);
        ++loaded;
    }
    CHECK(loaded >= 5);
}

TEST_CASE("Vehicle paints are drawn in the shares of the world's cars, the same for an id and seed",
          "[assets]") {
    double total = 0.0;
    std::map<std::string, int> drawn;
    for (const scene_viewer::VehiclePaint& p : scene_viewer::vehicle_paints()) {
        total += p.share;
        drawn[p.name] = 0;
    }
    CHECK(total == Approx(1.0));
    constexpr int kDraws = 20000;
    for (int i = 0; i < kDraws; ++i) {
        ++drawn[scene_viewer::vehicle_paint("car-" + std::to_string(i % 100), i / 100).name];
    }
    for (const scene_viewer::VehiclePaint& p : scene_viewer::vehicle_paints()) {
        INFO(p.name);
        // Binomial spread at 20,000 draws is at most 0.34 %; 1.5 % is over four of it.
        CHECK(drawn[p.name] / static_cast<double>(kDraws) == Approx(p.share).margin(0.015));
    }
    CHECK(scene_viewer::vehicle_paint("car-1", 5).name ==
          scene_viewer::vehicle_paint("car-1", 5).name);
    std::set<std::string> seen;
    for (std::uint64_t seed = 0; seed < 40; ++seed) {
        seen.insert(scene_viewer::vehicle_paint("car-1", seed).name);
    }
    CHECK(seen.size() >= 4);  // one id, many seeds: not one paint
}
