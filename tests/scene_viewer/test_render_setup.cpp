#include <functional>
#include <stdexcept>
#include <string>
#include <vector>

#include <catch2/catch.hpp>

#include "scene_viewer/bench/benchmark.hpp"
#include "scene_viewer/gfx/null_device.hpp"
#include "scene_viewer/render/render_setup.hpp"

using namespace scene_viewer;

namespace {

scene_schema::Entity entity(const std::string& cls, int id, double x, double z) {
    scene_schema::Entity e;
    e.id = cls + "-" + std::to_string(static_cast<int>(x * 10 + z));
    e.class_name = cls;
    e.class_id = id;
    e.x = x, e.y = 1.0, e.z = z;
    e.W = 2.0, e.H = 1.5, e.L = 4.0;
    return e;
}

std::string message_of(const std::function<void()>& f) {
    try {
        f();
    } catch (const std::invalid_argument& e) {
        return e.what();
    }
    return "";
}

}  // namespace

TEST_CASE("image sizes and points are read from text, refusing anything else", "[setup]") {
    CHECK(parse_image_size("640x480") == std::pair<int, int>{640, 480});
    CHECK(parse_image_size("2X3") == std::pair<int, int>{2, 3});
    CHECK(message_of([] { parse_image_size("640*480"); }) == "expected WxH, got '640*480'");
    CHECK(message_of([] { parse_image_size("640x480x2"); }) == "expected WxH, got '640x480x2'");
    CHECK(message_of([] { parse_image_size("0x10"); }) ==
          "each side must be in 1..16384, got '0x10'");
    CHECK_THROWS_AS(parse_image_size("16385x1"), std::invalid_argument);
    CHECK(parse_point_m("1,-2.5,3") == glm::vec3(1.0f, -2.5f, 3.0f));
    CHECK(message_of([] { parse_point_m("1,2"); }) == "expected x,y,z in metres, got '1,2'");
    CHECK_THROWS_AS(parse_point_m("1,2,3,"), std::invalid_argument);
}

TEST_CASE("each view has its default image size and the camera view takes the file's camera",
          "[setup]") {
    scene_schema::EntityDocument doc;
    CHECK(default_image_size(ViewKind::camera, doc) == std::pair<int, int>{1242, 375});
    CHECK(default_image_size(ViewKind::bev, doc) == std::pair<int, int>{800, 800});
    CHECK(default_image_size(ViewKind::chase, doc) == std::pair<int, int>{1280, 720});
    CHECK(default_image_size(ViewKind::free, doc) == std::pair<int, int>{1280, 720});
    doc.frame.camera = scene_schema::CameraIntrinsics{400, 200, 300, 300, 200, 100, 0.5};
    CHECK(default_image_size(ViewKind::camera, doc) == std::pair<int, int>{400, 200});
    CHECK(default_image_size(ViewKind::bev, doc) == std::pair<int, int>{800, 800});
}

TEST_CASE("a figure's tiles share one camera: the first file's, one BEV framing of all",
          "[setup]") {
    std::vector<scene_schema::EntityDocument> docs(2);
    docs[0].frame.camera = scene_schema::CameraIntrinsics{400, 200, 300, 300, 200, 100, 0.5};
    docs[0].entities.push_back(entity("car", 26, 0.0, 10.0));
    docs[1].entities.push_back(entity("car", 26, 0.0, 60.0));
    RenderOptions camera;
    share_view(docs, camera);
    REQUIRE(camera.view.intrinsics);
    CHECK(camera.view.intrinsics->width_px == 400);
    CHECK(camera.fit_bev);

    RenderOptions bev;
    bev.view.kind = ViewKind::bev;
    bev.width_px = bev.height_px = 800;
    share_view(docs, bev);
    CHECK_FALSE(bev.fit_bev);
    // Both cars (z 10 and 60) lie inside the shared framing.
    const float lo = bev.view.bev_centre_xz.y - bev.view.bev_half_height_m;
    const float hi = bev.view.bev_centre_xz.y + bev.view.bev_half_height_m;
    CHECK(lo < 8.0f);
    CHECK(hi > 62.0f);
    CHECK_THROWS_AS(share_view({}, bev), std::invalid_argument);
}

TEST_CASE("classes without a model are named, block classes are boxes by design", "[setup]") {
    NullDevice device;
    SceneRenderer renderer(device);
    scene_schema::EntityDocument doc;
    doc.entities.push_back(entity("car", 26, 0.0, 10.0));
    doc.entities.push_back(entity("building", 11, 5.0, 20.0));
    doc.entities.push_back(entity("train", 31, -5.0, 30.0));
    RenderOptions options;
    renderer.load(doc, nullptr, options);
    ClassTable table;
    table.classes.push_back(RenderClass{"building", 11, {70, 70, 70}, RenderKind::Block, {}, {}});
    CHECK(classes_missing_models(renderer, table) == std::vector<std::string>{"car", "train"});
}

TEST_CASE("a render laid over a background keeps the background where nothing was drawn",
          "[setup]") {
    ImageRgba8 render{2, 1, {255, 0, 0, 255, 0, 0, 0, 0}};
    const ImageRgba8 background{1, 1, {0, 0, 255, 255}};
    composite_background(render, background, 1.0f, Shading::semantic);
    CHECK(render.pixels == std::vector<std::uint8_t>{255, 0, 0, 255, 0, 0, 255, 255});
}

TEST_CASE("the benchmark times the default first and msaa only when asked", "[setup]") {
    const auto rows = benchmark_rows(4);
    REQUIRE(rows.size() == 4);
    CHECK(rows[0].name == "lit fxaa");
    CHECK(rows[1].name == "lit msaa 4");
    CHECK(rows[1].antialias == Antialias::msaa);
    CHECK(rows[3].shading == Shading::semantic);
    CHECK(benchmark_rows(1).size() == 3);
    CHECK(benchmark_rows(0)[1].name == "lit none");
}
