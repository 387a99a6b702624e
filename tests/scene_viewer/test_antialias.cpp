// Antialiasing of lit renders: the FXAA pass of the GL device (for real, on the headless
// context), its record in the null device, and the renderer's choice between FXAA, MSAA and none.
#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <stdexcept>

#include <catch2/catch.hpp>

#include "gl_test_context.hpp"
#include "scene_viewer/gfx/null_device.hpp"
#include "scene_viewer/render/image.hpp"
#include "scene_viewer/render/scene_renderer.hpp"
#include "scene_viewer/views/views.hpp"

using namespace scene_viewer;

namespace {

using testing::gl_device;

constexpr int kSize = 64;
const glm::vec4 kBackground{0.0f, 0.0f, 0.0f, 1.0f};
const glm::vec4 kForeground{1.0f, 1.0f, 1.0f, 1.0f};
/// The edge in pixels, rows from the top: y = kEdgeY0 + kEdgeSlope * x; shallow, so its stair
/// steps are 4 pixels long (FXAA's case), and it crosses the whole image.
constexpr double kEdgeY0 = 20.0;
constexpr double kEdgeSlope = 0.25;

/// Draws a flat white quad below a shallow diagonal edge on black, unlit, with or without FXAA.
ImageRgba8 render_edge(Device& device, bool fxaa) {
    // NDC: x = 2 u / kSize - 1, y = 1 - 2 v / kSize (GL y up, image rows down).
    auto ndc = [](double u, double v) {
        return glm::vec3(static_cast<float>(2.0 * u / kSize - 1.0),
                         static_cast<float>(1.0 - 2.0 * v / kSize), 0.0f);
    };
    MeshData quad;
    quad.positions = {ndc(0, kEdgeY0), ndc(kSize, kEdgeY0 + kEdgeSlope * kSize),
                      ndc(kSize, 2 * kSize), ndc(0, 2 * kSize)};
    quad.indices = {0, 1, 2, 0, 2, 3};
    const MeshHandle mesh = device.create_mesh(quad);
    FrameSetup setup;
    setup.width_px = setup.height_px = kSize;
    setup.clear_colour = kBackground;
    setup.fxaa = fxaa;
    device.begin_frame(setup);
    DrawCall call;
    call.mesh = mesh;
    call.colour = kForeground;
    call.lit = false;
    device.draw(call);
    device.end_frame();
    ImageRgba8 image = device.read_pixels();
    device.destroy_mesh(mesh);
    return image;
}

/// Distance in pixels of pixel (x, y)'s centre from the edge line.
double distance_from_edge(int x, int y) {
    const double u = x + 0.5, v = y + 0.5;
    return std::abs(v - kEdgeY0 - kEdgeSlope * u) / std::sqrt(1.0 + kEdgeSlope * kEdgeSlope);
}

struct EdgeStats {
    int intermediate = 0;          ///< grey pixels (neither colour)
    int far_changed = 0;           ///< pixels > 2 px from the edge that are not their flat colour
    int not_grey = 0;              ///< pixels whose channels differ (not a mix of black and white)
    int intermediate_far = 0;      ///< grey pixels > 2 px from the edge
    double max_step_across = 0.0;  ///< largest change between vertical neighbours, 0..255
};

EdgeStats edge_stats(const ImageRgba8& image) {
    EdgeStats s;
    for (int y = 0; y < image.height; ++y) {
        for (int x = 0; x < image.width; ++x) {
            const std::uint8_t* p = pixel_at(image, x, y);
            if (p[0] != p[1] || p[1] != p[2]) ++s.not_grey;
            const bool grey = p[0] != 0 && p[0] != 255;
            const double d = distance_from_edge(x, y);
            if (grey) ++s.intermediate;
            if (d > 2.0) {
                const bool below = y + 0.5 > kEdgeY0 + kEdgeSlope * (x + 0.5);
                if (p[0] != (below ? 255 : 0)) ++s.far_changed;
                if (grey) ++s.intermediate_far;
            }
            if (y > 0) {
                const int step = std::abs(int(p[0]) - int(pixel_at(image, x, y - 1)[0]));
                s.max_step_across = std::max(s.max_step_across, double(step));
            }
        }
    }
    return s;
}

}  // namespace

TEST_CASE("Without FXAA a hard diagonal edge between two flat colours has no intermediate pixels",
          "[gl][fxaa]") {
    const EdgeStats s = edge_stats(render_edge(gl_device(), false));
    CHECK(s.intermediate == 0);
    CHECK(s.far_changed == 0);
    CHECK(s.max_step_across == 255.0);
}

TEST_CASE("FXAA blends a hard diagonal edge and leaves the flat regions unchanged", "[gl][fxaa]") {
    const EdgeStats s = edge_stats(render_edge(gl_device(), true));
    // Most of the 64 columns get at least one grey pixel on the edge, none off it.
    CHECK(s.intermediate >= kSize / 2);
    CHECK(s.intermediate_far == 0);
    CHECK(s.far_changed == 0);
    CHECK(s.not_grey == 0);
    // The stair steps are softened: no column jumps from black to white in one row.
    CHECK(s.max_step_across < 255.0);
}

TEST_CASE("FXAA leaves a frame without edges exactly unchanged", "[gl][fxaa]") {
    Device& device = gl_device();
    FrameSetup setup;
    setup.width_px = 32;
    setup.height_px = 16;
    setup.clear_colour = {0.2f, 0.4f, 0.6f, 1.0f};
    setup.fxaa = true;
    device.begin_frame(setup);
    device.end_frame();
    const ImageRgba8 image = device.read_pixels();
    const std::uint8_t expected[4] = {51, 102, 153, 255};
    int differing = 0;
    for (std::size_t i = 0; i < image.pixels.size(); ++i) {
        if (image.pixels[i] != expected[i % 4]) ++differing;
    }
    CHECK(differing == 0);
}

TEST_CASE("A frame setup asking for both MSAA and FXAA is rejected by both devices", "[gl][fxaa]") {
    FrameSetup setup;
    setup.width_px = setup.height_px = 8;
    setup.msaa_samples = 4;
    setup.fxaa = true;
    NullDevice null_device;
    CHECK_THROWS_AS(null_device.begin_frame(setup), std::invalid_argument);
    CHECK_THROWS_AS(gl_device().begin_frame(setup), std::invalid_argument);
}

TEST_CASE("Lit renders default to FXAA and the null device records one FXAA pass per frame",
          "[ecs][fxaa]") {
    const auto doc = scene_schema::read_file(STEREOSCENE_SAMPLES_DIR "/baselines/street.json");
    NullDevice device;
    SceneRenderer renderer(device);
    RenderOptions options;
    options.width_px = 160;
    options.height_px = 90;
    options.view = chase_view();
    CHECK(options.antialias == Antialias::fxaa);
    renderer.render(doc, nullptr, options);
    renderer.render_frame();
    CHECK(device.fxaa_passes == 2);
    CHECK(device.last_setup.fxaa);
    CHECK(device.last_setup.msaa_samples == 0);

    options.antialias = Antialias::msaa;
    renderer.render(doc, nullptr, options);
    CHECK(device.fxaa_passes == 2);
    CHECK_FALSE(device.last_setup.fxaa);
    CHECK(device.last_setup.msaa_samples == 4);

    options.antialias = Antialias::none;
    renderer.render(doc, nullptr, options);
    CHECK_FALSE(device.last_setup.fxaa);
    CHECK(device.last_setup.msaa_samples == 0);

    for (Shading shading : {Shading::semantic, Shading::instance}) {
        for (Antialias antialias : {Antialias::fxaa, Antialias::msaa}) {
            options.shading = shading;
            options.antialias = antialias;
            renderer.render(doc, nullptr, options);
            CHECK_FALSE(device.last_setup.fxaa);
            CHECK(device.last_setup.msaa_samples == 0);
        }
    }
    CHECK(device.fxaa_passes == 2);
    CHECK(device.frames_ended == 8);
}

TEST_CASE("Antialiasing names parse and unknown ones are rejected", "[fxaa]") {
    CHECK(parse_antialias("fxaa") == Antialias::fxaa);
    CHECK(parse_antialias("msaa") == Antialias::msaa);
    CHECK(parse_antialias("none") == Antialias::none);
    CHECK_THROWS_AS(parse_antialias("ssaa"), std::invalid_argument);
    CHECK_THROWS_AS(parse_antialias("FXAA"), std::invalid_argument);
}

TEST_CASE("Semantic and instance renders are byte-identical whatever the antialiasing",
          "[gl][fxaa][semantic]") {
    const auto doc = scene_schema::read_file(STEREOSCENE_SAMPLES_DIR "/baselines/street.json");
    SceneRenderer renderer(gl_device());
    RenderOptions options;
    options.width_px = 320;
    options.height_px = 180;
    options.view = chase_view();
    for (Shading shading : {Shading::semantic, Shading::instance}) {
        options.shading = shading;
        options.antialias = Antialias::none;
        const ImageRgba8 plain = renderer.render(doc, nullptr, options);
        for (Antialias antialias : {Antialias::fxaa, Antialias::msaa}) {
            options.antialias = antialias;
            CHECK(renderer.render(doc, nullptr, options).pixels == plain.pixels);
        }
    }
}

TEST_CASE("On the street's geometric edges FXAA comes closer to 4x MSAA than no antialiasing",
          "[gl][fxaa]") {
    const auto doc = scene_schema::read_file(STEREOSCENE_SAMPLES_DIR "/baselines/street.json");
    SceneRenderer renderer(gl_device());
    RenderOptions options;
    options.width_px = 640;
    options.height_px = 360;
    options.view = chase_view();
    auto render = [&](Antialias antialias) {
        options.antialias = antialias;
        return renderer.render(doc, nullptr, options);
    };
    const ImageRgba8 msaa = render(Antialias::msaa);
    const ImageRgba8 fxaa = render(Antialias::fxaa);
    const ImageRgba8 none = render(Antialias::none);
    // Edge pixels: those that multisampling changes. Away from them (more than 1 px) FXAA may
    // only touch a few pixels (luma edges inside a model: faces meeting at an angle).
    const int w = none.width, h = none.height;
    auto changed = [&](const ImageRgba8& image, int x, int y) {
        return !std::equal(pixel_at(image, x, y), pixel_at(image, x, y) + 3, pixel_at(none, x, y));
    };
    double fxaa_error = 0.0, none_error = 0.0;
    int edge_pixels = 0, fxaa_changed = 0, fxaa_changed_off_edges = 0;
    for (int y = 0; y < h; ++y) {
        for (int x = 0; x < w; ++x) {
            if (changed(fxaa, x, y)) {
                ++fxaa_changed;
                bool near_edge = false;
                for (int dy = -1; dy <= 1; ++dy) {
                    for (int dx = -1; dx <= 1; ++dx) {
                        const int u = x + dx, v = y + dy;
                        if (u >= 0 && v >= 0 && u < w && v < h && changed(msaa, u, v))
                            near_edge = true;
                    }
                }
                if (!near_edge) ++fxaa_changed_off_edges;
            }
            if (!changed(msaa, x, y)) continue;
            ++edge_pixels;
            for (int c = 0; c < 3; ++c) {
                const int reference = pixel_at(msaa, x, y)[c];
                fxaa_error += std::abs(pixel_at(fxaa, x, y)[c] - reference);
                none_error += std::abs(pixel_at(none, x, y)[c] - reference);
            }
        }
    }
    INFO(edge_pixels << " edge pixels: mean |fxaa - msaa| " << fxaa_error / edge_pixels / 3
                     << ", mean |none - msaa| " << none_error / edge_pixels / 3 << "; FXAA changed "
                     << fxaa_changed << " pixels, " << fxaa_changed_off_edges << " off the edges");
    REQUIRE(edge_pixels > 1000);
    CHECK(fxaa_error < 0.75 * none_error);
    CHECK(fxaa_changed_off_edges < fxaa_changed / 4);
}

TEST_CASE("Compositing over a background adds only an edge pixel's covered share of the model",
          "[fxaa][composite]") {
    const Rgb8 clear = kLitBackground;
    const Rgb8 model{0, 0, 200};
    const Rgb8 background{50, 50, 50};
    // Three pixels: uncovered (the clear colour, alpha 0), an edge half covered, fully covered.
    ImageRgba8 render = make_image(3, 1, clear, 0);
    std::uint8_t* edge = &render.pixels[4];
    for (int c = 0; c < 3; ++c) edge[c] = static_cast<std::uint8_t>((model[c] + clear[c] + 1) / 2);
    edge[3] = 128;
    std::uint8_t* full = &render.pixels[8];
    std::copy(model.begin(), model.end(), full);
    full[3] = 255;

    SECTION("opaque: the edge is half model, half background, with no trace of the clear colour") {
        composite_over(render, make_image(3, 1, background), 1.0f, clear);
        for (int c = 0; c < 3; ++c) {
            CHECK(render.pixels[c] == background[c]);
            CHECK(std::abs(render.pixels[4 + c] - (model[c] + background[c]) / 2.0) <= 1.0);
            CHECK(render.pixels[8 + c] == model[c]);
        }
    }
    SECTION("opacity 0.6: covered pixels mix 60 % model, the edge half of that") {
        composite_over(render, make_image(3, 1, background), 0.6f, clear);
        for (int c = 0; c < 3; ++c) {
            CHECK(render.pixels[c] == background[c]);
            CHECK(std::abs(render.pixels[4 + c] -
                           (background[c] + 0.3 * (model[c] - background[c]))) <= 1.0);
            CHECK(std::abs(render.pixels[8 + c] - (0.4 * background[c] + 0.6 * model[c])) <= 0.5);
        }
    }
    for (int i = 3; i < 12; i += 4) CHECK(render.pixels[i] == 255);
}

TEST_CASE("One device switches antialiasing, shading and size between frames without leftovers",
          "[gl][fxaa]") {
    const auto doc = scene_schema::read_file(STEREOSCENE_SAMPLES_DIR "/baselines/street.json");
    SceneRenderer renderer(gl_device());
    RenderOptions options;
    options.width_px = 160;
    options.height_px = 90;
    options.view = chase_view();
    const ImageRgba8 first = renderer.render(doc, nullptr, options);
    options.shading = Shading::semantic;
    const ImageRgba8 semantic = renderer.render(doc, nullptr, options);
    options.shading = Shading::lit;
    options.antialias = Antialias::msaa;
    options.width_px = 200;
    options.height_px = 100;
    renderer.render(doc, nullptr, options);
    options.antialias = Antialias::none;
    options.width_px = 160;
    options.height_px = 90;
    renderer.render(doc, nullptr, options);
    options.antialias = Antialias::fxaa;
    CHECK(renderer.render(doc, nullptr, options).pixels == first.pixels);
    options.shading = Shading::semantic;
    CHECK(renderer.render(doc, nullptr, options).pixels == semantic.pixels);
}
