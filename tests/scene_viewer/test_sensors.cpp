// Synthetic stereo sensors: real llvmpipe renders of tiny scenes with known answers, and the
// CPU parts (sensor model, calibration text, PNG encoding, instance ids) on their own.
#include <algorithm>
#include <cmath>
#include <limits>
#include <string>
#include <vector>

#include <catch2/catch.hpp>

#include "gl_test_context.hpp"
#include "scene_viewer/assets/class_table.hpp"
#include "scene_viewer/assets/image_io.hpp"
#include "scene_viewer/assets/palette.hpp"
#include "scene_viewer/assets/vehicle_paints.hpp"
#include "scene_viewer/gfx/null_device.hpp"
#include "scene_viewer/render/scene_renderer.hpp"
#include "scene_viewer/sensors/stereo_sensors.hpp"
#include "stereoscene/support/angles.hpp"

using stereoscene::support::kPi;

using namespace scene_viewer;

namespace {

/// A small rig: 320 x 160 px, f = 300 px, principal point at the image centre, 0.5 m baseline.
StereoRig small_rig() {
    StereoRig rig;
    rig.width_px = 320;
    rig.height_px = 160;
    rig.fx_px = rig.fy_px = 300.0;
    rig.cx_px = 160.0;
    rig.cy_px = 80.0;
    rig.baseline_m = 0.5;
    return rig;
}

SensorOptions small_options() {
    SensorOptions o;
    o.rig = small_rig();
    o.ground_underlay = false;
    return o;
}

scene_schema::Entity box(const std::string& id, const std::string& cls, int class_id, double x,
                         double y, double z, double w, double h, double l) {
    scene_schema::Entity e;
    e.id = id;
    e.class_name = cls;
    e.class_id = class_id;
    e.x = x, e.y = y, e.z = z;
    e.theta = -kPi / 2;  // length along +z
    e.W = w, e.H = h, e.L = l;
    return e;
}

scene_schema::EntityDocument scene(std::vector<scene_schema::Entity> entities) {
    scene_schema::EntityDocument doc;
    doc.frame.id = "sensors";
    doc.entities = std::move(entities);
    return doc;
}

StereoFrame render(const scene_schema::EntityDocument& doc, const SensorOptions& options) {
    SceneRenderer renderer(testing::gl_device());
    return render_stereo_frame(renderer, doc, options);
}

std::size_t at(const StereoRig& rig, int x, int y) {
    return static_cast<std::size_t>(y) * rig.width_px + x;
}

Rgb8 rgb(const ImageRgb8& image, int x, int y) {
    const std::size_t i = (static_cast<std::size_t>(y) * image.width + x) * 3;
    return {image.pixels[i], image.pixels[i + 1], image.pixels[i + 2]};
}

/// Sum of squared differences of a patch of the left image at (x, y) and the right image at
/// (x - shift, y), over the three channels.
double ssd(const StereoFrame& f, int x, int y, int half, int shift) {
    double sum = 0.0;
    for (int dy = -half; dy <= half; ++dy) {
        for (int dx = -half; dx <= half; ++dx) {
            const Rgb8 l = rgb(f.left, x + dx, y + dy);
            const Rgb8 r = rgb(f.right, x + dx - shift, y + dy);
            for (int c = 0; c < 3; ++c) {
                const double d = static_cast<double>(l[c]) - r[c];
                sum += d * d;
            }
        }
    }
    return sum;
}

}  // namespace

TEST_CASE("A box at known depth gives the GT disparity fx B / z at its centre pixel",
          "[sensors][gl]") {
    // A wall 4 m wide whose front face is at z = 10 - 0.25 = 9.75 m, centred on the optical axis.
    const auto doc = scene({box("wall", "building", 11, 0.0, 0.0, 10.0, 4.0, 3.0, 0.5)});
    const SensorOptions options = small_options();
    const StereoFrame f = render(doc, options);
    const StereoRig& rig = f.rig;
    const double expected = rig.fx_px * rig.baseline_m / 9.75;
    const std::size_t centre = at(rig, 160, 80);
    CHECK(f.disparity.values[centre] / 256.0 == Approx(expected).margin(0.5));
    CHECK(f.disparity.values[centre] / 256.0 == Approx(expected).margin(0.02));
    CHECK(f.depth_m[centre] == Approx(9.75).margin(0.005));
    CHECK(f.depth_mm.values[centre] == Approx(9750).margin(5));
    // Nothing drawn in the corner (no underlay): no disparity, no depth, sky.
    CHECK(f.disparity.values[at(rig, 0, 0)] == 0);
    CHECK(f.depth_mm.values[at(rig, 0, 0)] == 0);
    CHECK(rgb(f.semantic, 0, 0) == Rgb8{70, 130, 180});
}

TEST_CASE("The right image is the left one shifted by the GT disparity", "[sensors][gl]") {
    // A textured wall at 7.75 m: d = 300 * 0.5 / 7.75 = 19.35 px.
    const auto doc = scene({box("wall", "building", 11, 0.0, 0.0, 8.0, 8.0, 4.0, 0.5)});
    // The geometry alone: no noise, no blur, equal gains.
    SensorOptions options = small_options();
    options.sensor.noise_sigma = 0.0;
    options.sensor.blur_sigma_px = 0.0;
    options.sensor.right_gain = 1.0;
    const StereoFrame f = render(doc, options);
    const int x = 170, y = 80, half = 7;
    const double d = f.disparity.values[at(f.rig, x, y)] / 256.0;
    REQUIRE(d == Approx(19.35).margin(0.05));
    int best = -1;
    double best_ssd = std::numeric_limits<double>::max(), worst_ssd = 0.0;
    for (int shift = 0; shift <= 40; ++shift) {
        const double s = ssd(f, x, y, half, shift);
        if (s < best_ssd) best_ssd = s, best = shift;
        worst_ssd = std::max(worst_ssd, s);
    }
    CHECK(std::abs(best - d) <= 1.0);
    // Sub-pixel: a parabola through the costs around the best shift lands on d.
    REQUIRE(best > 0);
    const double c0 = ssd(f, x, y, half, best - 1), c1 = best_ssd,
                 c2 = ssd(f, x, y, half, best + 1);
    const double refined = best + 0.5 * (c0 - c2) / (c0 - 2.0 * c1 + c2);
    CHECK(refined == Approx(d).margin(0.5));
    // The texture makes the match distinct: other shifts cost far more than the right one.
    CHECK(ssd(f, x, y, half, best + 4) > 3.0 * best_ssd);
    CHECK(ssd(f, x, y, half, best - 4) > 3.0 * best_ssd);
    CHECK(worst_ssd > 10.0 * best_ssd);
}

TEST_CASE("The semantic image shows the class colour at the projected centre", "[sensors][gl]") {
    // Car centre (1, 0.5, 12): u = 300 * 1 / 12 + 160 = 185, v = 300 * 0.5 / 12 + 80 = 92.5.
    const auto doc = scene({box("car-1", "car", 26, 1.0, 0.5, 12.0, 1.8, 1.5, 4.2),
                            box("person-1", "person", 24, -2.0, 0.8, 10.0, 0.6, 1.7, 0.5)});
    SensorOptions options = small_options();
    options.ground_underlay = true;
    const StereoFrame f = render(doc, options);
    CHECK(rgb(f.semantic, 185, 92) == Rgb8{0, 0, 142});
    // Person: u = 300 * -2 / 10 + 160 = 100, v = 300 * 0.8 / 10 + 80 = 104.
    CHECK(rgb(f.semantic, 100, 104) == Rgb8{220, 20, 60});
    // The underlay fills the ground below the horizon (terrain), the sky is above it.
    CHECK(rgb(f.semantic, 5, 155) == Rgb8{152, 251, 152});
    CHECK(rgb(f.semantic, 5, 5) == Rgb8{70, 130, 180});
    // Every semantic pixel is an exact palette colour.
    for (int y = 0; y < f.rig.height_px; y += 7) {
        for (int x = 0; x < f.rig.width_px; x += 7) {
            const Rgb8 c = rgb(f.semantic, x, y);
            const bool known = c == Rgb8{0, 0, 142} || c == Rgb8{220, 20, 60} ||
                               c == Rgb8{152, 251, 152} || c == Rgb8{70, 130, 180};
            CHECK(known);
        }
    }
}

TEST_CASE("Two cars get distinct KITTI instance ids, stuff gets instance 0", "[sensors][gl]") {
    const auto doc = scene({box("building-1", "building", 11, 0.0, -1.0, 30.0, 20.0, 10.0, 4.0),
                            box("car-a", "car", 26, -2.0, 0.5, 12.0, 1.8, 1.5, 4.2),
                            box("car-b", "car", 26, 2.0, 0.5, 12.0, 1.8, 1.5, 4.2)});
    const StereoFrame f = render(doc, small_options());
    // Car centres: u = 160 -+ 50, v = 92.5.
    CHECK(f.instance.values[at(f.rig, 110, 92)] == (26 << 8 | 1));
    CHECK(f.instance.values[at(f.rig, 210, 92)] == (26 << 8 | 2));
    CHECK(f.instance.values[at(f.rig, 160, 60)] == (11 << 8));
    CHECK(f.instance.values[at(f.rig, 0, 0)] == 0);
}

TEST_CASE("A car half hidden behind another is about half visible and stuff has no record",
          "[sensors][gl]") {
    // car-near (1.8 x 1.5 m front face at 7.7 m) ends at u = 160 + 300 * 0.9 / 7.7 = 195;
    // car-far's front face (3.6 x 0.75 m at 15.7 m, x 0..3.6 m) spans u 160..229 and rows inside
    // car-near's: about half of it is hidden.
    const auto doc = scene({box("building-1", "building", 11, 0.0, -1.0, 40.0, 30.0, 10.0, 4.0),
                            box("car-near", "car", 26, 0.0, 0.5, 8.0, 1.8, 1.5, 0.6),
                            box("car-far", "car", 26, 1.8, 0.5, 16.0, 3.6, 0.75, 0.6),
                            box("person-1", "person", 24, -40.0, 0.0, 10.0, 0.6, 1.7, 0.6)});
    const StereoFrame f = render(doc, small_options());
    REQUIRE(f.visibility.size() == 3);  // the building is stuff
    const EntityVisibility& near = f.visibility[0];
    const EntityVisibility& far = f.visibility[1];
    const EntityVisibility& person = f.visibility[2];
    CHECK(near.id == "car-near");
    CHECK(near.instance == (26 << 8 | 1));
    CHECK(far.instance == (26 << 8 | 2));
    CHECK(near.visible_px == near.unoccluded_px);
    CHECK(near.visible_fraction() == 1.0);
    // Far car alone: about 69 x 14 px.
    CHECK(far.unoccluded_px > 800);
    CHECK(far.visible_fraction() == Approx(0.5).margin(0.08));
    std::size_t far_in_image = 0;
    for (const auto v : f.instance.values) far_in_image += v == far.instance;
    CHECK(far.visible_px == far_in_image);
    // The person is outside the image: no pixels either way.
    CHECK(person.unoccluded_px == 0);
    CHECK(person.visible_fraction() == 0.0);
    const std::string json = format_visibility_json(f);
    CHECK(json.find("\"id\": \"car-far\"") != std::string::npos);
    CHECK(json.find("\"unoccluded_px\": " + std::to_string(far.unoccluded_px)) !=
          std::string::npos);
    CHECK(kitti_layout_files(f, "000007").count("visibility/000007.json") == 1);
}

TEST_CASE("A car cut by the image border is as visible as the share of it inside the image",
          "[sensors][gl]") {
    // The image spans u 0..319 (cx 160, fx 300): the 3.6 x 0.6 m box centred on x = -6.0 m,
    // z = 10 m spans u -81..38 (its front face at 9.7 m, its inner side to 10.3 m), so about a
    // third of its columns, all of the same height, are in the image.
    const auto doc = scene({box("building-1", "building", 11, 0.0, -1.0, 40.0, 30.0, 10.0, 4.0),
                            box("car-cut", "car", 26, -6.0, 0.5, 10.0, 3.6, 1.5, 0.6),
                            box("car-whole", "car", 26, 1.0, 0.5, 10.0, 1.8, 1.5, 0.6)});
    const StereoFrame f = render(doc, small_options());
    REQUIRE(f.visibility.size() == 2);
    const EntityVisibility& cut = f.visibility[0];
    const EntityVisibility& whole = f.visibility[1];
    CHECK(cut.visible_px == cut.unoccluded_px);  // nothing hides it
    CHECK(cut.in_view_fraction == Approx(38.0 / 119.0).margin(0.05));
    CHECK(cut.visible_fraction() == Approx(cut.in_view_fraction));
    CHECK(whole.in_view_fraction == 1.0);
    CHECK(whole.visible_fraction() == 1.0);
    CHECK(format_visibility_json(f).find("\"in_view_fraction\"") != std::string::npos);
}

TEST_CASE("Rig presets set the size, intrinsics and baseline and keep the camera height",
          "[sensors]") {
    StereoRig base;
    base.camera_height_m = 1.2;
    const StereoRig argoverse = rig_preset("argoverse", base);
    CHECK(argoverse.width_px == 2464);
    CHECK(argoverse.height_px == 2056);
    CHECK(argoverse.fx_px == 3894.0);
    CHECK(argoverse.fy_px == 3894.0);
    CHECK(argoverse.baseline_m == 0.30);
    CHECK(argoverse.camera_height_m == 1.2);
    CHECK(rig_preset("kitti", base).fx_px == StereoRig{}.fx_px);
    for (const auto& name : rig_preset_names()) CHECK_NOTHROW(rig_preset(name, base).validate());
    CHECK_THROWS_WITH(rig_preset("bumblebee", base),
                      Catch::Contains("bumblebee") && Catch::Contains("realsense"));
}

TEST_CASE("KITTI instance ids count per class in file order", "[sensors]") {
    const std::vector<std::uint16_t> ids = kitti_instance_ids({26, 7, 26, 24, 26, 11});
    const std::vector<std::uint16_t> expected = {26 << 8 | 1, 7 << 8,      26 << 8 | 2,
                                                 24 << 8 | 1, 26 << 8 | 3, 11 << 8};
    CHECK(ids == expected);
    CHECK_THROWS_AS(kitti_instance_ids(std::vector<int>(256, 26)), std::invalid_argument);
    CHECK_THROWS_AS(kitti_instance_ids({300}), std::invalid_argument);
}

TEST_CASE("Sensor renders are deterministic: same seed same bytes, another seed other noise",
          "[sensors][gl]") {
    const auto doc = scene({box("wall", "building", 11, 0.0, 0.0, 8.0, 8.0, 4.0, 0.5),
                            box("car-1", "car", 26, 1.0, 0.5, 6.0, 1.8, 1.5, 4.2)});
    SensorOptions options = small_options();
    options.sensor.seed = 7;
    const StereoFrame a = render(doc, options);
    const StereoFrame b = render(doc, options);
    CHECK(a.left.pixels == b.left.pixels);
    CHECK(a.right.pixels == b.right.pixels);
    options.sensor.seed = 8;
    const StereoFrame c = render(doc, options);
    CHECK(a.left.pixels != c.left.pixels);
    CHECK(a.right.pixels != c.right.pixels);
    // Only the noise differs: ground truth is the same, and the images differ by a few levels.
    CHECK(a.disparity.values == c.disparity.values);
    CHECK(a.semantic.pixels == c.semantic.pixels);
    double sum = 0.0;
    for (std::size_t i = 0; i < a.left.pixels.size(); ++i)
        sum += std::abs(static_cast<int>(a.left.pixels[i]) - c.left.pixels[i]);
    const double mean_abs = sum / static_cast<double>(a.left.pixels.size());
    CHECK(mean_abs > 1.0);
    CHECK(mean_abs < 6.0);
}

TEST_CASE("World paints recolour the shipped car in the colour images only", "[sensors][gl]") {
    // The car's back faces the camera; its lower body (0.25-0.8 m of 1.4 m) is at v ~ 112.
    const auto doc = scene({box("car-1", "car", 26, 0.0, 0.5, 10.0, 1.8, 1.5, 4.2)});
    SensorOptions options = small_options();
    options.sensor.noise_sigma = 0.0;
    options.sensor.blur_sigma_px = 0.0;
    // A seed that paints it red.
    while (std::string(vehicle_paint("car-1", options.sensor.seed).name) != "red") {
        ++options.sensor.seed;
    }
    SceneRenderer renderer(testing::gl_device());
    use_class_models(renderer, load_class_table(default_class_table_path()));
    const StereoFrame own = render_stereo_frame(renderer, doc, options);
    options.vehicle_paints = true;
    const StereoFrame painted = render_stereo_frame(renderer, doc, options);
    const Rgb8 before = rgb(own.left, 160, 112), after = rgb(painted.left, 160, 112);
    CHECK(before[2] > before[0] + 40);  // the class colour: dark blue
    CHECK(after[0] > after[2] + 40);    // red
    CHECK(painted.semantic.pixels == own.semantic.pixels);
    CHECK(painted.instance.values == own.instance.values);
    CHECK(painted.disparity.values == own.disparity.values);
}

TEST_CASE("The sensor model adds Gaussian noise of the given sigma and the right camera's gain",
          "[sensors]") {
    ImageRgb8 grey{200, 100, std::vector<std::uint8_t>(200 * 100 * 3, 128)};
    SensorModelOptions o;
    o.blur_sigma_px = 0.0;
    o.noise_sigma = 3.0;
    o.right_gain = 0.9;
    for (int camera : {0, 1}) {
        const ImageRgb8 out = apply_sensor_model(grey, camera, o);
        double sum = 0.0, sum2 = 0.0;
        for (std::uint8_t v : out.pixels) sum += v, sum2 += static_cast<double>(v) * v;
        const double n = static_cast<double>(out.pixels.size());
        const double mean = sum / n, sd = std::sqrt(sum2 / n - mean * mean);
        CHECK(mean == Approx(camera == 0 ? 128.0 : 115.2).margin(0.1));
        CHECK(sd == Approx(3.0).margin(0.1));
    }
    o.vignetting = true;
    o.noise_sigma = 0.0;
    const ImageRgb8 v = apply_sensor_model(grey, 0, o);
    CHECK(v.pixels[(50 * 200 + 100) * 3] == 128);
    CHECK(v.pixels[0] < 100);
    SensorModelOptions bad;
    bad.right_gain = 0.0;
    CHECK_THROWS_WITH(apply_sensor_model(grey, 0, bad), Catch::Contains("right_gain"));
}

TEST_CASE("GT disparity linearises the depth buffer", "[sensors]") {
    const float n = 0.3f, far = 1000.0f;
    std::vector<float> window;
    for (double z : {1.0, 7.75, 40.0, 300.0}) {
        // Window depth of eye depth z under a GL perspective projection.
        const double nd = n, fd = far;
        const double ndc = ((fd + nd) - 2.0 * fd * nd / z) / (fd - nd);
        window.push_back(static_cast<float>(0.5 * ndc + 0.5));
    }
    window.push_back(1.0f);
    const std::vector<float> d = disparity_from_window_depth(window, 721.5377, 0.54, n, far);
    CHECK(d[0] == Approx(721.5377 * 0.54 / 1.0).epsilon(1e-4));
    CHECK(d[1] == Approx(721.5377 * 0.54 / 7.75).epsilon(1e-4));
    CHECK(d[2] == Approx(721.5377 * 0.54 / 40.0).epsilon(1e-3));
    CHECK(d[3] == Approx(721.5377 * 0.54 / 300.0).epsilon(2e-2));
    CHECK(d[4] == 0.0f);
}

TEST_CASE("The calibration file round-trips through KITTI's calib_cam_to_cam format",
          "[sensors][calib]") {
    const StereoRig rig;  // KITTI's
    const std::string text = format_kitti_calib(rig);
    CHECK(text.find("P_rect_03: 7.215377000000e+02 0.000000000000e+00 6.095593000000e+02 "
                    "-3.896") != std::string::npos);
    CHECK(text.find("R_rect_02: 1.0") != std::string::npos);
    const StereoRig back = parse_kitti_calib(text);
    CHECK(back.width_px == 1242);
    CHECK(back.height_px == 375);
    CHECK(back.fx_px == Approx(rig.fx_px).epsilon(1e-12));
    CHECK(back.fy_px == Approx(rig.fy_px).epsilon(1e-12));
    CHECK(back.cx_px == Approx(rig.cx_px).epsilon(1e-12));
    CHECK(back.cy_px == Approx(rig.cy_px).epsilon(1e-12));
    CHECK(back.baseline_m == Approx(0.54).epsilon(1e-12));
    std::string broken = text;
    broken.erase(broken.find("P_rect_03"));
    CHECK_THROWS_WITH(parse_kitti_calib(broken), Catch::Contains("P_rect_03"));
}

TEST_CASE("A rig takes the entity file's intrinsics and scales with the image size", "[sensors]") {
    scene_schema::EntityDocument doc;
    doc.frame.camera = scene_schema::CameraIntrinsics{640, 480, 500, 510, 320, 240, 0.3};
    const StereoRig rig = rig_for(doc, StereoRig{});
    CHECK(rig.width_px == 640);
    CHECK(rig.fy_px == 510);
    CHECK(rig.baseline_m == 0.3);
    CHECK(rig.camera_height_m == 1.65);
    const StereoRig half = StereoRig{}.resized(621, 188);
    CHECK(half.fx_px == Approx(721.5377 / 2));
    CHECK(half.cy_px == Approx(172.854 * 188 / 375));
}

TEST_CASE("The PNG encoder writes RGB and 16-bit images that decode back", "[sensors][png]") {
    ImageRgb8 rgb_image{5, 3, {}};
    for (int i = 0; i < 5 * 3 * 3; ++i)
        rgb_image.pixels.push_back(static_cast<std::uint8_t>(i * 5));
    const auto rgb_png = encode_png_rgb8(rgb_image);
    const ImageRgba8 back = decode_image_memory(rgb_png.data(), rgb_png.size(), "rgb");
    REQUIRE(back.width == 5);
    REQUIRE(back.height == 3);
    for (int p = 0; p < 15; ++p) {
        for (int c = 0; c < 3; ++c) CHECK(back.pixels[p * 4 + c] == rgb_image.pixels[p * 3 + c]);
    }
    ImageU16 ids{4, 2, {26 << 8 | 1, 26 << 8 | 2, 11 << 8, 0, 65535, 256, 7 << 8, 24 << 8 | 3}};
    const auto u16_png = encode_png_u16(ids);
    CHECK(u16_png[24] == 16);  // IHDR bit depth
    CHECK(u16_png[25] == 0);   // grey
    const ImageRgba8 grey = decode_image_memory(u16_png.data(), u16_png.size(), "u16");
    REQUIRE(grey.width == 4);
    for (int p = 0; p < 8; ++p) CHECK(grey.pixels[p * 4] == ids.values[p] >> 8);
}

TEST_CASE("The sensor pipeline runs on the null backend: all sky, no disparity", "[sensors][ecs]") {
    NullDevice device;
    SceneRenderer renderer(device);
    const auto doc = scene({box("car-1", "car", 26, 1.0, 0.5, 12.0, 1.8, 1.5, 4.2)});
    const StereoFrame f = render_stereo_frame(renderer, doc, small_options());
    // left, right, semantic, instance, car-1 alone and alone seen wider
    CHECK(device.frames_begun == 6);
    CHECK(f.left.width == 320);
    CHECK(rgb(f.semantic, 160, 80) == Rgb8{70, 130, 180});
    CHECK(std::all_of(f.disparity.values.begin(), f.disparity.values.end(),
                      [](std::uint16_t v) { return v == 0; }));
    CHECK(std::all_of(f.instance.values.begin(), f.instance.values.end(),
                      [](std::uint16_t v) { return v == 0; }));
    // The last frame was car-1's instance pass alone: one draw, coloured (26, 1, 0) / 255.
    REQUIRE(device.draws.size() == 1);
    CHECK(device.draws[0].colour.r * 255.0f == Approx(26.0f));
    CHECK(device.draws[0].colour.g * 255.0f == Approx(1.0f));
    REQUIRE(f.visibility.size() == 1);
    CHECK(f.visibility[0].unoccluded_px == 0);  // the null device draws nothing
}

TEST_CASE("Where nothing is drawn the colour images show the sky gradient", "[sensors][gl]") {
    const auto doc = scene({box("car-1", "car", 26, 1.0, 0.5, 12.0, 1.8, 1.5, 4.2)});
    SensorOptions options = small_options();
    options.sensor.noise_sigma = 0.0;
    options.sensor.blur_sigma_px = 0.0;
    options.sensor.right_gain = 1.0;
    const StereoFrame f = render(doc, options);
    for (const ImageRgb8* image : {&f.left, &f.right}) {
        const Rgb8 top = rgb(*image, 5, 0), horizon = rgb(*image, 5, 80), low = rgb(*image, 5, 150);
        CHECK(std::abs(top[0] - 78) <= 2);
        CHECK(std::abs(top[2] - 196) <= 2);
        CHECK(horizon == Rgb8{196, 212, 228});
        CHECK(low == Rgb8{196, 212, 228});
    }
    // The car is drawn (textured body), not sky.
    CHECK(rgb(f.left, 185, 92) != rgb(f.left, 5, 92));
}

TEST_CASE("Label bleed moves thing borders by at most N px, both ways, the same for a seed",
          "[sensors]") {
    // A 40 x 30 px car (instance 26 << 8 | 1) in a 96 x 64 road image.
    const int w = 96, h = 64;
    ImageU16 instance{w, h, std::vector<std::uint16_t>(w * h, 7 << 8)};
    ImageRgb8 semantic{w, h, std::vector<std::uint8_t>(w * h * 3, 0)};
    const auto inside = [](int x, int y) { return x >= 28 && x < 68 && y >= 17 && y < 47; };
    for (int y = 0; y < h; ++y) {
        for (int x = 0; x < w; ++x) {
            const std::size_t i = static_cast<std::size_t>(y) * w + x;
            if (inside(x, y)) instance.values[i] = 26 << 8 | 1;
            const std::uint8_t colour[3] = {128, 64, 128};
            const std::uint8_t car[3] = {0, 0, 142};
            for (int c = 0; c < 3; ++c)
                semantic.pixels[i * 3 + c] = inside(x, y) ? car[c] : colour[c];
        }
    }
    const int bleed = 3;
    const ImageRgb8 out = apply_label_bleed(semantic, instance, bleed, 7);
    int grown = 0, shrunk = 0, far_changed = 0;
    for (int y = 0; y < h; ++y) {
        for (int x = 0; x < w; ++x) {
            const std::size_t i = static_cast<std::size_t>(y) * w + x;
            if (out.pixels[i * 3 + 2] == semantic.pixels[i * 3 + 2]) continue;
            // Chessboard distance to the car's border.
            const int dx = std::max({28 - x, x - 67, 0}), dy = std::max({17 - y, y - 46, 0});
            const int outside = std::max(dx, dy);
            const int in = std::min({x - 27, 68 - x, y - 16, 47 - y});
            if (inside(x, y)) {
                ++shrunk;
                if (in > bleed) ++far_changed;
            } else {
                ++grown;
                if (outside > bleed) ++far_changed;
            }
        }
    }
    CHECK(grown > 0);
    CHECK(shrunk > 0);
    CHECK(far_changed == 0);
    CHECK(apply_label_bleed(semantic, instance, bleed, 7).pixels == out.pixels);
    CHECK(apply_label_bleed(semantic, instance, bleed, 8).pixels != out.pixels);
    CHECK(apply_label_bleed(semantic, instance, 0, 7).pixels == semantic.pixels);
    instance.width = 10;
    CHECK_THROWS_AS(apply_label_bleed(semantic, instance, bleed, 7), std::invalid_argument);
}
