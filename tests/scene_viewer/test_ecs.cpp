#include <cmath>
#include <set>

#include <catch2/catch.hpp>
#include <glm/glm.hpp>

#include "scene_viewer/assets/vehicle_paints.hpp"
#include "scene_viewer/ecs/coordinates.hpp"
#include "scene_viewer/ecs/world.hpp"
#include "scene_viewer/gfx/null_device.hpp"
#include "scene_viewer/render/scene_renderer.hpp"
#include "scene_viewer/systems/camera_system.hpp"
#include "scene_viewer/systems/transform_system.hpp"
#include "stereoscene/support/angles.hpp"

using stereoscene::support::kPi;

using namespace scene_viewer;

namespace {

scene_schema::Entity entity(const std::string& cls, int id, glm::dvec3 centre, double theta,
                            glm::dvec3 whl) {
    scene_schema::Entity e;
    e.id = cls + "-" + std::to_string(static_cast<int>(centre.x * 10 + centre.z));
    e.class_name = cls;
    e.class_id = id;
    e.x = centre.x, e.y = centre.y, e.z = centre.z;
    e.theta = theta;
    e.W = whl.x, e.H = whl.y, e.L = whl.z;
    return e;
}

scene_schema::EntityDocument one_car(double theta) {
    scene_schema::EntityDocument doc;
    doc.frame.id = "test";
    doc.frame.camera = scene_schema::CameraIntrinsics{400, 200, 300, 300, 200, 100, 0.5};
    doc.entities.push_back(entity("car", 26, {5, 1, 20}, theta, {2, 1.5, 4}));
    return doc;
}

glm::vec3 apply(const glm::mat4& m, glm::vec3 p) { return glm::vec3(m * glm::vec4(p, 1.0f)); }

bool near(glm::vec3 a, glm::vec3 b) { return glm::length(a - b) < 1e-4f; }

}  // namespace

TEST_CASE("Component pools store components contiguously and find them by entity", "[ecs]") {
    World world;
    const EntityId a = world.create(), b = world.create(), c = world.create();
    world.transforms.set(a, Transform{{1, 2, 3}, 0.0, {1, 1, 1}});
    world.transforms.set(c, Transform{{4, 5, 6}, 0.0, {1, 1, 1}});
    CHECK(world.transforms.size() == 2);
    CHECK(world.transforms.has(a));
    CHECK_FALSE(world.transforms.has(b));
    REQUIRE(world.transforms.get(c) != nullptr);
    CHECK(world.transforms.get(c)->centre_kitti.z == 6.0f);
    CHECK(world.transforms.owners() == std::vector<EntityId>{a, c});
    world.transforms.set(a, Transform{{9, 9, 9}, 0.0, {1, 1, 1}});
    CHECK(world.transforms.size() == 2);
    CHECK(world.transforms.dense()[0].centre_kitti.x == 9.0f);
    world.clear();
    CHECK(world.entity_count() == 0);
    CHECK(world.transforms.size() == 0);
}

TEST_CASE("for_each visits the entities that have every component, in the first pool's order",
          "[ecs]") {
    World world;
    const EntityId a = world.create(), b = world.create(), c = world.create();
    world.meshes.set(c, MeshRef{3});
    world.meshes.set(a, MeshRef{1});
    world.meshes.set(b, MeshRef{2});
    world.materials.set(a, Material{});
    world.materials.set(c, Material{});
    world.sources.set(c, SourceEntity{0, "c", 26, "car"});
    world.sources.set(b, SourceEntity{1, "b", 26, "car"});

    std::vector<EntityId> seen;
    for_each([&](EntityId e, MeshRef&, Material&) { seen.push_back(e); }, world.meshes,
             world.materials);
    CHECK(seen == std::vector<EntityId>{c, a});  // b has no material

    seen.clear();
    for_each([&](EntityId e, MeshRef&, Material&, SourceEntity&) { seen.push_back(e); },
             world.meshes, world.materials, world.sources);
    CHECK(seen == std::vector<EntityId>{c});

    // Components are handed out by reference: writes land in the pools.
    for_each([](EntityId, MeshRef& m) { m.model += 10; }, world.meshes);
    CHECK(world.meshes.get(b)->model == 12);

    // Const pools give const components, and the join is driven by the first pool.
    const World& view = world;
    std::uint32_t sum = 0;
    for_each([&](EntityId, const SourceEntity&, const MeshRef& m) { sum += m.model; }, view.sources,
             view.meshes);
    CHECK(sum == 13 + 12);
    const World empty;
    seen.clear();
    for_each([&](EntityId e, const Material&) { seen.push_back(e); }, empty.materials);
    CHECK(seen.empty());
}

TEST_CASE("An entity becomes one draw whose world matrix places, turns and scales the box",
          "[ecs][systems]") {
    NullDevice device;
    SceneRenderer renderer(device);
    RenderOptions options;
    options.width_px = 400;
    options.height_px = 200;
    options.shading = Shading::semantic;
    renderer.render(one_car(0.0), nullptr, options);

    REQUIRE(device.frames_begun == 1);
    REQUIRE(device.frames_ended == 1);
    REQUIRE(device.draws.size() == 1);  // camera view: no ego car, no grid
    const DrawCall& d = device.draws.front();
    // Centre at (5, 1, 20) KITTI.
    CHECK(near(apply(d.model, {0, 0, 0}), kitti_to_gl({5, 1, 20})));
    // theta = 0: the front (+Z of the model) points along KITTI +x, L/2 = 2 m ahead.
    CHECK(near(apply(d.model, {0, 0, 0.5f}), kitti_to_gl({7, 1, 20})));
    // W = 2 across the heading (KITTI z), H = 1.5 vertical (top is KITTI y - 0.75).
    CHECK(std::abs(glm::length(apply(d.model, {0.5f, 0, 0}) - kitti_to_gl({5, 1, 20})) - 1.0f) <
          1e-4f);
    CHECK(near(apply(d.model, {0, 0.5f, 0}), kitti_to_gl({5, 0.25f, 20})));
    // Semantic shading: the exact palette colour, unlit.
    CHECK(d.colour == glm::vec4(0, 0, 142 / 255.0f, 1));
    CHECK_FALSE(d.lit);
}

TEST_CASE("Turning an entity by 90 degrees turns its world matrix about the vertical axis",
          "[ecs][systems]") {
    NullDevice device;
    SceneRenderer renderer(device);
    RenderOptions options;
    renderer.render(one_car(-kPi / 2), nullptr, options);
    REQUIRE(device.draws.size() == 1);
    // theta = -pi/2 heads forward (+z KITTI).
    CHECK(near(apply(device.draws[0].model, {0, 0, 0.5f}), kitti_to_gl({5, 1, 22})));
    CHECK(device.draws[0].lit);
}

TEST_CASE("A class model is fitted by its bounds into the entity box", "[ecs][systems]") {
    NullDevice device;
    SceneRenderer renderer(device);
    Model model;
    MeshPrimitive prim;
    prim.positions = {{-1, 0, -3}, {1, 2, 3}, {1, 0, 3}};
    prim.normals = {{0, 1, 0}, {0, 1, 0}, {0, 1, 0}};
    prim.indices = {0, 1, 2};
    model.primitives.push_back(prim);
    model.bounds_min = {-1, 0, -3};
    model.bounds_max = {1, 2, 3};
    renderer.set_class_model("car", model);
    RenderOptions options;
    renderer.render(one_car(-kPi / 2), nullptr, options);
    REQUIRE(device.draws.size() == 1);
    const glm::mat4& m = device.draws[0].model;
    // Model-frame bounds corners land on the box corners: the box spans x 4..6, y 0.25..1.75,
    // z 18..22 (KITTI); the model's front (+Z) points forward, its top (+Y) up (smaller y).
    CHECK(near(apply(m, {0, 1, 3}), kitti_to_gl({5, 1, 22})));
    CHECK(near(apply(m, {0, 2, 0}), kitti_to_gl({5, 0.25f, 20})));
    CHECK(near(apply(m, {0, 0, 0}), kitti_to_gl({5, 1.75f, 20})));
}

TEST_CASE("Uploaded meshes are kept across frames: rendering again uploads nothing",
          "[ecs][performance]") {
    NullDevice device;
    SceneRenderer renderer(device);
    RenderOptions options;
    const auto doc = one_car(0.0);
    renderer.load(doc, nullptr, options);
    renderer.render_frame();
    const std::size_t meshes = device.meshes.size();
    for (int i = 0; i < 5; ++i) renderer.render_frame();
    CHECK(device.meshes.size() == meshes);
    CHECK(device.frames_ended == 6);
}

TEST_CASE("The chase view draws the ego car and the BEV view adds a line grid", "[ecs][views]") {
    NullDevice device;
    SceneRenderer renderer(device);
    RenderOptions options;
    options.view = chase_view();
    renderer.render(one_car(0.0), nullptr, options);
    CHECK(device.draws.size() == 2);

    options.view.kind = ViewKind::bev;
    renderer.render(one_car(0.0), nullptr, options);
    REQUIRE(device.draws.size() == 3);
    bool has_lines = false;
    for (const auto& d : device.draws) {
        if (device.meshes.at(d.mesh.id - 1).topology == Topology::lines) has_lines = true;
    }
    CHECK(has_lines);

    options.grid = false;
    options.ego = false;
    renderer.render(one_car(0.0), nullptr, options);
    CHECK(device.draws.size() == 1);
}

TEST_CASE("Ground classes become flat patches on the bottom face of their box", "[ecs][systems]") {
    NullDevice device;
    SceneRenderer renderer(device);
    scene_schema::EntityDocument doc;
    doc.frame.id = "ground";
    doc.entities.push_back(entity("road", 7, {0, 1.5, 20}, -kPi / 2, {8, 0.4, 40}));
    RenderOptions options;
    options.view.kind = ViewKind::free;
    options.ego = false;
    renderer.render(doc, nullptr, options);
    REQUIRE(device.draws.size() == 1);
    const glm::mat4& m = device.draws[0].model;
    // Height clamped to 0.1 m, resting on the box bottom (KITTI y = 1.7).
    CHECK(near(apply(m, {0, -0.5f, 0}), kitti_to_gl({0, 1.7f, 20})));
    CHECK(near(apply(m, {0, 0.5f, 0}), kitti_to_gl({0, 1.6f, 20})));
}

TEST_CASE("A point cloud becomes one points draw with per-vertex class colours in semantic mode",
          "[ecs][cloud]") {
    NullDevice device;
    SceneRenderer renderer(device);
    PointCloud cloud;
    cloud.positions_kitti = {{0, 1, 10}, {1, 1, 10}};
    cloud.colours = {{10, 20, 30}, {40, 50, 60}};
    cloud.class_ids = {7, 26};
    RenderOptions options;
    options.shading = Shading::semantic;
    renderer.render(one_car(0.0), &cloud, options);
    REQUIRE(device.draws.size() == 2);
    const DrawCall& points = device.draws[1];
    const MeshData& mesh = device.meshes.at(points.mesh.id - 1);
    CHECK(mesh.topology == Topology::points);
    REQUIRE(mesh.colours.size() == 2);
    CHECK(mesh.colours[0] == glm::vec4(128 / 255.0f, 64 / 255.0f, 128 / 255.0f, 1));
    CHECK(mesh.colours[1] == glm::vec4(0, 0, 142 / 255.0f, 1));
    CHECK(points.vertex_colour);
    // Points are stored in KITTI metres; the world matrix converts them.
    CHECK(near(apply(points.model, {0, 1, 10}), {0, -1, -10}));
}

TEST_CASE("The camera system gives the frame's camera an identity pose", "[ecs][views]") {
    World world;
    Camera camera;
    camera.spec.kind = ViewKind::camera;
    camera.spec.intrinsics = scene_schema::CameraIntrinsics{400, 200, 300, 300, 200, 100, 0.5};
    camera.width_px = 400;
    camera.height_px = 200;
    world.cameras.set(world.create(), camera);
    update_cameras(world);
    CHECK(world.cameras.dense()[0].view == glm::mat4(1.0f));
}

TEST_CASE("Render options refuse absurd image sizes naming the field", "[ecs][options]") {
    RenderOptions options;
    options.width_px = 0;
    CHECK_THROWS_WITH(options.validate(), Catch::Contains("width_px"));
    options.width_px = 20000;
    CHECK_THROWS_WITH(options.validate(), Catch::Contains("width_px"));
    options.width_px = 100;
    options.height_px = kMaxImageSide + 1;
    CHECK_THROWS_WITH(options.validate(), Catch::Contains("height_px"));
    // 16384^2 is fine with one target but not with 4 samples per pixel or FXAA's second target.
    options.width_px = options.height_px = kMaxImageSide;
    options.shading = Shading::semantic;
    CHECK_NOTHROW(options.validate());
    options.shading = Shading::lit;
    options.antialias = Antialias::none;
    CHECK_NOTHROW(options.validate());
    options.antialias = Antialias::fxaa;
    CHECK_THROWS_WITH(options.validate(), Catch::Contains("fxaa"));
    options.antialias = Antialias::msaa;
    options.msaa_samples = 4;
    CHECK_THROWS_WITH(options.validate(), Catch::Contains("msaa_samples"));
}

TEST_CASE("A textured model uploads its texture once and lit draws bind it", "[ecs][systems]") {
    NullDevice device;
    SceneRenderer renderer(device);
    Model model;
    MeshPrimitive prim;
    prim.positions = {{-1, 0, -1}, {1, 0, -1}, {0, 1, 1}};
    prim.normals = {{0, 1, 0}, {0, 1, 0}, {0, 1, 0}};
    prim.texcoords = {{0, 0}, {1, 0}, {0.5f, 1}};
    prim.indices = {0, 1, 2};
    prim.texture = 0;
    prim.base_colour = {0.5f, 0.5f, 0.5f, 1.0f};
    model.primitives.push_back(prim);
    model.textures.push_back(ImageRgba8{1, 1, {255, 0, 0, 255}});
    model.bounds_min = {-1, 0, -1};
    model.bounds_max = {1, 1, 1};
    renderer.set_class_model("car", model);
    CHECK(device.textures_created == 1);

    RenderOptions options;
    renderer.render(one_car(0.0), nullptr, options);
    REQUIRE(device.draws.size() == 1);
    CHECK(device.draws[0].texture.valid());
    // Lit models keep their own colour: the linear base colour 0.5 encoded to sRGB (~0.735).
    CHECK(device.draws[0].colour.r == Approx(0.7354).margin(1e-3));

    options.shading = Shading::semantic;
    renderer.render(one_car(0.0), nullptr, options);
    REQUIRE(device.draws.size() == 1);
    CHECK_FALSE(device.draws[0].texture.valid());
    CHECK(device.draws[0].colour == glm::vec4(0, 0, 142 / 255.0f, 1));
    CHECK(device.textures_created == 1);
}

TEST_CASE("A class's low model draws its boxes lower than they are long or wide",
          "[ecs][systems][export]") {
    NullDevice device;
    SceneRenderer renderer(device);
    const auto triangle = [](float top) {
        Model m;
        MeshPrimitive prim;
        prim.positions = {{-1, 0, -1}, {1, top, 1}, {1, 0, 1}};
        prim.normals = {{0, 1, 0}, {0, 1, 0}, {0, 1, 0}};
        prim.indices = {0, 1, 2};
        m.primitives.push_back(prim);
        m.bounds_min = {-1, 0, -1};
        m.bounds_max = {1, top, 1};
        return m;
    };
    renderer.set_class_model("vegetation", triangle(4.0f));        // a tree
    renderer.set_class_model("vegetation", triangle(0.5f), true);  // a hedge
    scene_schema::EntityDocument doc;
    doc.entities.push_back(entity("vegetation", 21, {5, -1, 20}, 0.0, {2.6, 5.6, 2.6}));
    doc.entities.push_back(entity("vegetation", 21, {7, 1, 20}, -kPi / 2, {0.9, 1.2, 3.0}));
    doc.entities.push_back(entity("vegetation", 21, {-7, 1, 20}, 0.0, {1.5, 1.2, 1.0}));
    RenderOptions options;
    options.ego = false;
    renderer.load(doc, nullptr, options);
    const std::vector<PlacedModel> placed = renderer.placed_models();
    REQUIRE(placed.size() == 3);
    CHECK(placed[0].model->bounds_max.y == 4.0f);
    CHECK(placed[1].model->bounds_max.y == 0.5f);
    CHECK(placed[2].model->bounds_max.y == 0.5f);  // wider than tall: a bush
    // Without a low model every box gets the class's model.
    SceneRenderer plain(device);
    plain.set_class_model("vegetation", triangle(4.0f));
    plain.load(doc, nullptr, options);
    for (const PlacedModel& p : plain.placed_models()) CHECK(p.model->bounds_max.y == 4.0f);
}

TEST_CASE("World paints replace a vehicle model's paint parts and nothing else", "[ecs][systems]") {
    NullDevice device;
    SceneRenderer renderer(device);
    Model car;
    for (const char* name : {"paint", "glass"}) {
        MeshPrimitive prim;
        prim.positions = {{-1, 0, -2}, {1, 1.5f, 2}, {1, 0, 2}};
        prim.normals = {{0, 1, 0}, {0, 1, 0}, {0, 1, 0}};
        prim.indices = {0, 1, 2};
        prim.material_name = name;
        car.primitives.push_back(prim);
    }
    car.bounds_min = {-1, 0, -2};
    car.bounds_max = {1, 1.5f, 2};
    renderer.set_class_model("car", car);
    renderer.set_class_model("vegetation", car);
    auto doc = one_car(0.0);
    doc.entities.push_back(entity("vegetation", 21, {5, -1, 20}, 0.0, {2.6, 5.6, 2.6}));
    RenderOptions options;
    options.ego = false;
    renderer.render(doc, nullptr, options);
    REQUIRE(device.draws.size() == 4);
    const glm::vec4 own = device.draws[0].colour;
    options.vehicle_paints = true;
    options.paint_seed = 3;
    renderer.render(doc, nullptr, options);
    REQUIRE(device.draws.size() == 4);
    const Rgb8 paint = vehicle_paint(doc.entities[0].id, 3).srgb;
    CHECK(device.draws[0].colour ==
          glm::vec4(paint[0] / 255.0f, paint[1] / 255.0f, paint[2] / 255.0f, 1.0f));
    CHECK(device.draws[1].colour == own);  // the glass keeps its colour
    CHECK(device.draws[2].colour == own);  // vegetation wears no paint
    // Semantic shading draws the class colour whatever the paint.
    options.shading = Shading::semantic;
    renderer.render(doc, nullptr, options);
    CHECK(device.draws[0].colour == glm::vec4(0, 0, 142 / 255.0f, 1));
}

TEST_CASE("The assembled scene places every entity with the matrix it is drawn with",
          "[ecs][export]") {
    NullDevice device;
    SceneRenderer renderer(device);
    Model car;
    MeshPrimitive prim;
    prim.positions = {{-1, 0, -2}, {1, 1.5f, 2}, {1, 0, 2}};
    prim.normals = {{0, 1, 0}, {0, 1, 0}, {0, 1, 0}};
    prim.indices = {0, 1, 2};
    car.primitives.push_back(prim);
    car.bounds_min = {-1, 0, -2};
    car.bounds_max = {1, 1.5f, 2};
    renderer.set_class_model("car", car);

    auto doc = one_car(0.3);
    doc.entities.push_back(entity("wall", 12, {-6, 0, 30}, -kPi / 2, {0.3, 2, 10}));
    doc.entities.push_back(entity("road", 7, {0, 1.6, 20}, -kPi / 2, {7, 0.05, 40}));
    RenderOptions options;
    options.view = chase_view();
    renderer.load(doc, nullptr, options);
    renderer.render_frame();
    const std::vector<PlacedModel> placed = renderer.placed_models();
    // Three entities and the ego car; draws are in the same order.
    REQUIRE(placed.size() == 4);
    REQUIRE(device.draws.size() == 4);
    for (std::size_t i = 0; i < placed.size(); ++i) {
        CHECK(placed[i].world == device.draws[i].model);
    }
    CHECK(placed[0].name == doc.entities[0].id);
    CHECK(placed[0].model->primitives.size() == 1);
    CHECK(placed[0].model->bounds_max == glm::vec3(1, 1.5f, 2));  // the class model itself
    CHECK(placed[3].name == "ego");
    // The wall has no model: a box in the wall's class colour (linear).
    REQUIRE(placed[1].model != nullptr);
    CHECK(placed[1].model->primitives.at(0).base_colour.b ==
          Approx(std::pow((156 / 255.0 + 0.055) / 1.055, 2.4)).epsilon(1e-3));
    // Road is a patch by design; only the wall is reported as a box for want of a model.
    CHECK(renderer.classes_drawn_as_boxes() == std::set<std::string>{"wall"});
}

TEST_CASE("Replacing a class model frees the old model's meshes and textures", "[ecs][models]") {
    NullDevice device;
    {
        SceneRenderer renderer(device);
        Model model;
        MeshPrimitive prim;
        prim.positions = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}};
        prim.texcoords = {{0, 0}, {1, 0}, {0, 1}};
        prim.indices = {0, 1, 2};
        prim.texture = 0;
        model.primitives = {prim, prim};
        model.textures.push_back(ImageRgba8{1, 1, {1, 2, 3, 255}});
        renderer.set_class_model("car", model);
        renderer.set_class_model("car", model);
        CHECK(device.meshes_destroyed == 2);
        CHECK(device.textures_destroyed == 1);
    }
    // The renderer's destructor frees the rest: 2 + 1 class meshes, the box, 1 texture.
    CHECK(device.meshes_destroyed == 5);
    CHECK(device.textures_destroyed == 2);
}
