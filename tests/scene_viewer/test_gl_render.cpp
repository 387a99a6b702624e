// GL tests: they render for real on the headless context (llvmpipe on CPU-only machines). If EGL
// cannot start, they fail.
#include <cmath>
#include <cstdlib>
#include <memory>

#include <catch2/catch.hpp>

#include "gl_test_context.hpp"
#include "scene_viewer/assets/class_table.hpp"
#include "scene_viewer/assets/image_io.hpp"
#include "scene_viewer/ecs/coordinates.hpp"
#include "scene_viewer/gfx/gl_device.hpp"
#include "scene_viewer/platform/headless_context.hpp"
#include "scene_viewer/render/image.hpp"
#include "scene_viewer/render/scene_renderer.hpp"
#include "stereoscene/support/angles.hpp"

using stereoscene::support::kPi;

using namespace scene_viewer;

namespace {

using testing::gl;
using testing::gl_device;

scene_schema::Entity entity(const std::string& cls, int id, glm::dvec3 centre, double theta,
                            glm::dvec3 whl) {
    static int n = 0;
    scene_schema::Entity e;
    e.id = cls + "-" + std::to_string(++n);
    e.class_name = cls;
    e.class_id = id;
    e.x = centre.x, e.y = centre.y, e.z = centre.z;
    e.theta = theta;
    e.W = whl.x, e.H = whl.y, e.L = whl.z;
    return e;
}

const scene_schema::CameraIntrinsics kCamera{400, 200, 300, 300, 200, 100, 0.5};

Rgb8 rgb_at(const ImageRgba8& image, int x, int y) {
    const std::uint8_t* p = pixel_at(image, x, y);
    return {p[0], p[1], p[2]};
}

/// Pixel of a KITTI point in the camera view at the intrinsics' own size.
std::pair<int, int> project(const glm::dvec3& p) {
    return {static_cast<int>(std::floor(kCamera.fx_px * p.x / p.z + kCamera.cx_px)),
            static_cast<int>(std::floor(kCamera.fy_px * p.y / p.z + kCamera.cy_px))};
}

/// Semantic BEV of a 20 x 20 m square centred at x = 0, z = 20: 10 px per metre.
RenderOptions bev_options() {
    RenderOptions o;
    o.width_px = 200;
    o.height_px = 200;
    o.shading = Shading::semantic;
    o.view.kind = ViewKind::bev;
    o.fit_bev = false;
    o.view.bev_centre_xz = {0.0f, 20.0f};
    o.view.bev_half_height_m = 10.0f;
    o.grid = false;
    o.ego = false;
    return o;
}

struct Footprint {
    int count = 0;
    int min_x = 1 << 30, max_x = -1, min_y = 1 << 30, max_y = -1;
    double centroid_x = 0.0, centroid_y = 0.0;
};

/// Pixels of `colour` in columns [0, x_end) (default: all).
Footprint footprint(const ImageRgba8& image, Rgb8 colour, int x_end = -1) {
    Footprint f;
    if (x_end < 0) x_end = image.width;
    for (int y = 0; y < image.height; ++y) {
        for (int x = 0; x < x_end; ++x) {
            if (rgb_at(image, x, y) != colour) continue;
            ++f.count;
            f.min_x = std::min(f.min_x, x), f.max_x = std::max(f.max_x, x);
            f.min_y = std::min(f.min_y, y), f.max_y = std::max(f.max_y, y);
            f.centroid_x += x + 0.5, f.centroid_y += y + 0.5;
        }
    }
    if (f.count > 0) f.centroid_x /= f.count, f.centroid_y /= f.count;
    return f;
}

constexpr Rgb8 kCar{0, 0, 142};

}  // namespace

TEST_CASE("The headless context is an OpenGL 4.5 core context", "[gl]") {
    const GlInfo info = gl().context.info();
    CHECK(info.version.rfind("4.", 0) == 0);
    CHECK_FALSE(info.renderer.empty());
}

TEST_CASE("In flat semantic mode each entity's projected centre shows its class colour",
          "[gl][semantic]") {
    scene_schema::EntityDocument doc;
    doc.frame.id = "semantic";
    doc.frame.camera = kCamera;
    doc.entities = {entity("road", 7, {0, 1.65, 30}, -kPi / 2, {8, 0.05, 40}),
                    entity("car", 26, {-3, 0.9, 15}, -kPi / 2, {1.8, 1.5, 4.2}),
                    entity("person", 24, {2.5, 0.8, 10}, 0.3, {0.6, 1.7, 0.5}),
                    entity("building", 11, {12, -3, 40}, -kPi / 2, {10, 12, 14}),
                    entity("vegetation", 21, {-9, -1, 25}, 0.0, {2.5, 5, 2.5}),
                    entity("unknown-thing", 99, {-4, -2, 20}, 0.0, {1, 1, 1})};
    SceneRenderer renderer(gl_device());
    RenderOptions options;
    options.width_px = kCamera.width_px;
    options.height_px = kCamera.height_px;
    options.shading = Shading::semantic;
    const ImageRgba8 image = renderer.render(doc, nullptr, options);
    REQUIRE(image.width == 400);
    REQUIRE(image.height == 200);
    for (const auto& e : doc.entities) {
        const auto [u, v] = project({e.x, e.y, e.z});
        INFO(e.class_name << " at pixel " << u << "," << v);
        REQUIRE(u >= 0);
        REQUIRE(u < 400);
        REQUIRE(v >= 0);
        REQUIRE(v < 200);
        CHECK(rgb_at(image, u, v) == class_colour(e.class_id, e.class_name));
    }
    // Nothing was drawn at the top-left corner (sky): the semantic background.
    CHECK(rgb_at(image, 0, 0) == kSemanticBackground);
}

TEST_CASE("A car turned by 90 degrees swaps the width and height of its BEV footprint",
          "[gl][bev]") {
    SceneRenderer renderer(gl_device());
    scene_schema::EntityDocument doc;
    doc.frame.id = "bev";
    doc.entities = {entity("car", 26, {0, 0.9, 20}, -kPi / 2, {2, 1.5, 4})};
    const Footprint along = footprint(renderer.render(doc, nullptr, bev_options()), kCar);
    doc.entities[0].theta = 0.0;
    const Footprint across = footprint(renderer.render(doc, nullptr, bev_options()), kCar);
    // 10 px per metre: heading forward the car is 2 m wide and 4 m tall in the image.
    CHECK(along.max_x - along.min_x + 1 == Approx(20).margin(1));
    CHECK(along.max_y - along.min_y + 1 == Approx(40).margin(1));
    CHECK(across.max_x - across.min_x + 1 == Approx(40).margin(1));
    CHECK(across.max_y - across.min_y + 1 == Approx(20).margin(1));
    CHECK(along.count == Approx(800).epsilon(0.05));
    CHECK(across.count == Approx(800).epsilon(0.05));
}

TEST_CASE("A car at x = +5 appears right of centre in the BEV and farther cars appear higher",
          "[gl][bev]") {
    SceneRenderer renderer(gl_device());
    scene_schema::EntityDocument doc;
    doc.frame.id = "bev";
    doc.entities = {entity("car", 26, {5, 0.9, 25}, -kPi / 2, {2, 1.5, 4})};
    const Footprint f = footprint(renderer.render(doc, nullptr, bev_options()), kCar);
    REQUIRE(f.count > 0);
    CHECK(f.centroid_x == Approx(100 + 50).margin(1.0));  // 5 m right of centre
    CHECK(f.centroid_y == Approx(100 - 50).margin(1.0));  // 5 m beyond the view centre (z = 20)
}

TEST_CASE("A point of the cloud overlay lands on its projected pixel with its class colour",
          "[gl][cloud]") {
    SceneRenderer renderer(gl_device());
    scene_schema::EntityDocument doc;
    doc.frame.id = "cloud";
    doc.frame.camera = kCamera;
    PointCloud cloud;
    cloud.positions_kitti = {{1.0f, 0.5f, 10.0f}, {-2.0f, 1.0f, 8.0f}};
    cloud.class_ids = {24, 26};
    RenderOptions options;
    options.width_px = kCamera.width_px;
    options.height_px = kCamera.height_px;
    options.shading = Shading::semantic;
    options.point_size_px = 3.0f;
    const ImageRgba8 image = renderer.render(doc, &cloud, options);
    for (std::size_t i = 0; i < cloud.size(); ++i) {
        const auto [u, v] = project(glm::dvec3(cloud.positions_kitti[i]));
        CHECK(rgb_at(image, u, v) == class_colour(cloud.class_ids[i], ""));
    }
}

TEST_CASE("One renderer renders many frames and the same frame twice gives the same image",
          "[gl][performance]") {
    SceneRenderer renderer(gl_device());
    const auto doc = scene_schema::read_file(STEREOSCENE_SAMPLES_DIR "/baselines/street.json");
    RenderOptions options;
    options.width_px = 160;
    options.height_px = 90;
    options.view = chase_view();
    renderer.load(doc, nullptr, options);
    const ImageRgba8 first = renderer.render_frame();
    for (int i = 0; i < 3; ++i) renderer.render_frame();
    const ImageRgba8 last = renderer.render_frame();
    CHECK(first.pixels == last.pixels);
}

/// Compares a render with a committed golden PNG: llvmpipe differs by a few levels between
/// CPUs, so small per-pixel differences are allowed, and a share `max_edge_share` of channel
/// values may differ by more (edge pixels).
void check_against_golden(const ImageRgba8& image, const char* golden_file, double max_edge_share) {
    const ImageRgba8 golden =
        decode_image(std::string(SCENE_VIEWER_TEST_DATA_DIR "/") + golden_file);
    REQUIRE(image.width == golden.width);
    REQUIRE(image.height == golden.height);
    std::size_t differing = 0;
    double sum = 0.0;
    for (std::size_t i = 0; i < image.pixels.size(); ++i) {
        const int d = std::abs(int(image.pixels[i]) - int(golden.pixels[i]));
        sum += d;
        if (d > 12) ++differing;
    }
    CHECK(sum / image.pixels.size() < 1.0);
    CHECK(static_cast<double>(differing) <
          max_edge_share * static_cast<double>(image.pixels.size()));
}

TEST_CASE("The lit chase view of the street sample matches the golden image", "[gl][golden]") {
    // Golden made with: scene-render samples/baselines/street.json --view chase --size 320x180
    //   --boxes --antialias msaa -o tests/scene_viewer/data/golden_street_chase_boxes.png
    SceneRenderer renderer(gl_device());
    const auto doc = scene_schema::read_file(STEREOSCENE_SAMPLES_DIR "/baselines/street.json");
    RenderOptions options;
    options.width_px = 320;
    options.height_px = 180;
    options.view = chase_view();
    options.antialias = Antialias::msaa;
    check_against_golden(renderer.render(doc, nullptr, options), "golden_street_chase_boxes.png",
                         0.005);
}

TEST_CASE("The semantic BEV of the street sample with its grid matches the golden image",
          "[gl][golden][bev]") {
    // Golden made with: scene-render samples/baselines/street.json --view bev --shading semantic
    //   --size 300x300 --boxes -o tests/scene_viewer/data/golden_street_bev_semantic_boxes.png
    SceneRenderer renderer(gl_device());
    const auto doc = scene_schema::read_file(STEREOSCENE_SAMPLES_DIR "/baselines/street.json");
    RenderOptions options;
    options.width_px = 300;
    options.height_px = 300;
    options.view.kind = ViewKind::bev;
    options.shading = Shading::semantic;
    // Flat colours without MSAA: only a few edge pixels may differ.
    check_against_golden(renderer.render(doc, nullptr, options),
                         "golden_street_bev_semantic_boxes.png", 0.0005);
}

TEST_CASE("With the project's glTF models each class keeps its semantic colour at its centre",
          "[gl][semantic][models]") {
    SceneRenderer renderer(gl_device());
    const ClassTable table =
        load_class_table(STEREOSCENE_SOURCE_DIR "/assets/classes/render_classes.json");
    CHECK(use_class_models(renderer, table) >= 5);
    scene_schema::EntityDocument doc;
    doc.frame.id = "models";
    doc.frame.camera = kCamera;
    doc.entities = {entity("car", 26, {-3, 0.9, 15}, -kPi / 2, {1.8, 1.5, 4.2}),
                    entity("car", 26, {3, 0.9, 15}, 0.0, {1.8, 1.5, 4.2}),
                    entity("building", 11, {12, -3, 40}, -kPi / 2, {10, 12, 14})};
    RenderOptions options;
    options.width_px = kCamera.width_px;
    options.height_px = kCamera.height_px;
    options.shading = Shading::semantic;
    const ImageRgba8 image = renderer.render(doc, nullptr, options);
    for (const auto& e : doc.entities) {
        const auto [u, v] = project({e.x, e.y, e.z});
        INFO(e.class_name << " at pixel " << u << "," << v);
        CHECK(rgb_at(image, u, v) == class_colour(e.class_id, e.class_name));
    }
    // The car model is not its box: its silhouette covers clearly less than the box's.
    SceneRenderer boxes(gl_device());
    const Footprint model_car = footprint(image, kCar, kCamera.width_px / 2);
    const Footprint box_car =
        footprint(boxes.render(doc, nullptr, options), kCar, kCamera.width_px / 2);
    REQUIRE(box_car.count > 100);
    CHECK(model_car.count < 0.95 * box_car.count);
    CHECK(model_car.count > 0.5 * box_car.count);
}
