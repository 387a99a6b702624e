#include "scene_viewer/sensors/stereo_sensors.hpp"

#include <algorithm>
#include <cmath>
#include <map>
#include <stdexcept>
#include <string>

#include "scene_viewer/assets/palette.hpp"
#include "scene_viewer/ecs/coordinates.hpp"
#include "scene_viewer/render/scene_renderer.hpp"
#include "stereoscene/support/angles.hpp"

using stereoscene::support::kPi;

namespace scene_viewer {

namespace {

/// Sky of the colour images: zenith colour at the top, horizon colour at and below the
/// principal row (a horizontal camera's horizon).
constexpr float kSkyZenith[3] = {78.0f, 128.0f, 196.0f};
constexpr float kSkyHorizon[3] = {196.0f, 212.0f, 228.0f};

/// Id of the ground underlay added under every sensor scene.
constexpr const char* kUnderlayId = "sensor-ground-underlay";

/// The colour image under the sky: the MSAA resolve of a frame cleared to the lit background
/// with alpha 0 holds alpha * surface + (1 - alpha) * background, so adding
/// (1 - alpha) * (sky - background) swaps the background for the sky, exact at edges too.
ImageRgb8 composite_sky(const ImageRgba8& render, double cy_px) {
    ImageRgb8 out;
    out.width = render.width;
    out.height = render.height;
    out.pixels.resize(static_cast<std::size_t>(render.width) * render.height * 3);
    for (int y = 0; y < render.height; ++y) {
        const float t =
            cy_px > 0 ? std::clamp(static_cast<float>((cy_px - y) / cy_px), 0.0f, 1.0f) : 0.0f;
        float sky[3];
        for (int c = 0; c < 3; ++c) sky[c] = kSkyHorizon[c] + t * (kSkyZenith[c] - kSkyHorizon[c]);
        for (int x = 0; x < render.width; ++x) {
            const std::size_t i = static_cast<std::size_t>(y) * render.width + x;
            const float alpha = render.pixels[i * 4 + 3] / 255.0f;
            for (int c = 0; c < 3; ++c) {
                const float v =
                    render.pixels[i * 4 + c] + (1.0f - alpha) * (sky[c] - kLitBackground[c]);
                out.pixels[i * 3 + c] =
                    static_cast<std::uint8_t>(std::lround(std::clamp(v, 0.0f, 255.0f)));
            }
        }
    }
    return out;
}

}  // namespace

double EntityVisibility::visible_fraction() const {
    return unoccluded_px == 0 ? 0.0
                              : in_view_fraction * static_cast<double>(visible_px) /
                                    static_cast<double>(unoccluded_px);
}

void StereoRig::validate() const {
    if (width_px < 1 || width_px > kMaxImageSide)
        throw std::invalid_argument("width_px must be in 1.." + std::to_string(kMaxImageSide));
    if (height_px < 1 || height_px > kMaxImageSide)
        throw std::invalid_argument("height_px must be in 1.." + std::to_string(kMaxImageSide));
    if (!(fx_px > 0.0)) throw std::invalid_argument("fx_px must be > 0");
    if (!(fy_px > 0.0)) throw std::invalid_argument("fy_px must be > 0");
    if (!std::isfinite(cx_px)) throw std::invalid_argument("cx_px must be finite");
    if (!std::isfinite(cy_px)) throw std::invalid_argument("cy_px must be finite");
    if (!(baseline_m > 0.0 && baseline_m < 100.0))
        throw std::invalid_argument("baseline_m must be in (0, 100) metres");
    if (!(camera_height_m > 0.0 && camera_height_m < 100.0))
        throw std::invalid_argument("camera_height_m must be in (0, 100) metres");
}

StereoRig StereoRig::resized(int width, int height) const {
    StereoRig r = *this;
    const double sx = static_cast<double>(width) / width_px;
    const double sy = static_cast<double>(height) / height_px;
    r.width_px = width;
    r.height_px = height;
    r.fx_px *= sx;
    r.cx_px *= sx;
    r.fy_px *= sy;
    r.cy_px *= sy;
    return r;
}

namespace {

struct RigPreset {
    const char* name;
    int width_px, height_px;
    double fx_px, cx_px, cy_px, baseline_m;
};

// Published calibrations (KITTI 2011_09_26 P_rect_02/03; Cityscapes' camera.json of its
// training cities) and data sheets of the sensor families (Argoverse 1 stereo pair, ZED 2 at
// HD720, RealSense D435 infrared pair at 1280x720), rounded.
constexpr RigPreset kRigPresets[] = {
    {"kitti", 1242, 375, 721.5377, 609.5593, 172.854, 0.54},
    {"cityscapes", 2048, 1024, 2262.52, 1096.98, 513.137, 0.209313},
    {"argoverse", 2464, 2056, 3894.0, 1232.0, 1028.0, 0.30},
    {"zed", 1280, 720, 700.0, 640.0, 360.0, 0.12},
    {"realsense", 1280, 720, 640.0, 640.0, 360.0, 0.05},
};

}  // namespace

const std::vector<std::string>& rig_preset_names() {
    static const std::vector<std::string> names = [] {
        std::vector<std::string> out;
        for (const auto& p : kRigPresets) out.emplace_back(p.name);
        return out;
    }();
    return names;
}

StereoRig rig_preset(const std::string& name, const StereoRig& base) {
    for (const auto& p : kRigPresets) {
        if (name != p.name) continue;
        StereoRig rig = base;
        rig.width_px = p.width_px;
        rig.height_px = p.height_px;
        rig.fx_px = p.fx_px;
        rig.fy_px = p.fx_px;
        rig.cx_px = p.cx_px;
        rig.cy_px = p.cy_px;
        rig.baseline_m = p.baseline_m;
        return rig;
    }
    std::string known;
    for (const auto& n : rig_preset_names()) known += (known.empty() ? "" : ", ") + n;
    throw std::invalid_argument("no rig preset '" + name + "' (" + known + ")");
}

StereoRig rig_for(const scene_schema::EntityDocument& document, const StereoRig& defaults) {
    StereoRig rig = defaults;
    if (const auto& k = document.frame.camera) {
        rig.width_px = k->width_px;
        rig.height_px = k->height_px;
        rig.fx_px = k->fx_px;
        rig.fy_px = k->fy_px;
        rig.cx_px = k->cx_px;
        rig.cy_px = k->cy_px;
        if (k->baseline_m > 0.0) rig.baseline_m = k->baseline_m;
    }
    return rig;
}

void SensorModelOptions::validate() const {
    if (!(noise_sigma >= 0.0 && noise_sigma <= 64.0))
        throw std::invalid_argument("noise_sigma must be in 0..64 levels");
    if (!(blur_sigma_px >= 0.0 && blur_sigma_px <= 10.0))
        throw std::invalid_argument("blur_sigma_px must be in 0..10 pixels");
    if (!(right_gain > 0.0 && right_gain <= 4.0))
        throw std::invalid_argument("right_gain must be in (0, 4]");
    if (!(vignetting_strength >= 0.0 && vignetting_strength <= 1.0))
        throw std::invalid_argument("vignetting_strength must be in 0..1");
}

void SensorOptions::validate() const {
    rig.validate();
    sensor.validate();
    if (msaa_samples < 0 || msaa_samples > 16)
        throw std::invalid_argument("msaa_samples must be in 0..16");
    if (!(underlay_size_m > 0.0)) throw std::invalid_argument("underlay_size_m must be > 0");
    if (!(near_m > 0.0f)) throw std::invalid_argument("near_m must be > 0");
    if (!(far_m > near_m)) throw std::invalid_argument("far_m must be > near_m");
    if (label_bleed_px < 0 || label_bleed_px > 16)
        throw std::invalid_argument("label_bleed_px must be in 0..16 pixels");
}

std::vector<float> disparity_from_window_depth(const std::vector<float>& window_depth, double fx_px,
                                               double baseline_m, float near_m, float far_m) {
    std::vector<float> disparity(window_depth.size(), 0.0f);
    const double n = near_m, f = far_m;
    for (std::size_t i = 0; i < window_depth.size(); ++i) {
        const double d = window_depth[i];
        if (d >= 1.0) continue;
        const double z = 2.0 * n * f / (f + n - (2.0 * d - 1.0) * (f - n));
        disparity[i] = static_cast<float>(fx_px * baseline_m / z);
    }
    return disparity;
}

namespace {

/// The document's entities, plus (when asked) a terrain underlay. The underlay is appended
/// after the file's entities, so their instance ids do not change; its top lies 1 cm under the
/// road level, under any road patch of the file.
scene_schema::EntityDocument scene_with_underlay(const scene_schema::EntityDocument& document,
                                                 const SensorOptions& options) {
    scene_schema::EntityDocument scene = document;
    if (!options.ground_underlay) return scene;
    scene_schema::Entity underlay;
    underlay.id = kUnderlayId;
    underlay.class_name = "terrain";
    underlay.class_id = 22;
    underlay.theta = -kPi / 2;
    underlay.W = underlay.L = options.underlay_size_m;
    underlay.H = 0.02;
    underlay.y = options.rig.camera_height_m + 0.02;
    scene.entities.push_back(underlay);
    return scene;
}

/// Render options of the rig's left camera: its intrinsics, procedural texture, MSAA.
RenderOptions rig_render_options(const SensorOptions& options) {
    const StereoRig& rig = options.rig;
    RenderOptions o;
    o.width_px = rig.width_px;
    o.height_px = rig.height_px;
    o.view.kind = ViewKind::camera;
    // GL samples pixel i at i + 0.5; KITTI/OpenCV put pixel i's centre at u = i. Shifting the
    // principal point by half a pixel makes the images match the calibration exactly.
    scene_schema::CameraIntrinsics k;
    k.width_px = rig.width_px;
    k.height_px = rig.height_px;
    k.fx_px = rig.fx_px;
    k.fy_px = rig.fy_px;
    k.cx_px = rig.cx_px + 0.5;
    k.cy_px = rig.cy_px + 0.5;
    k.baseline_m = rig.baseline_m;
    o.view.intrinsics = k;
    o.view.near_m = options.near_m;
    o.view.far_m = options.far_m;
    o.fit_bev = false;
    o.grid = false;
    o.ego = false;
    o.keep_alpha = true;
    o.procedural_texture = true;
    o.vehicle_paints = options.vehicle_paints;
    o.paint_seed = options.sensor.seed;
    o.antialias = Antialias::msaa;
    o.msaa_samples = options.msaa_samples;
    return o;
}

/// The semantic (sky where nothing was drawn), instance, disparity and depth images of the
/// left view from its semantic and instance renders and window depth.
void fill_ground_truth(StereoFrame& frame, const ImageRgba8& semantic, const ImageRgba8& instance,
                       const std::vector<float>& window_depth, const SensorOptions& options) {
    const StereoRig& rig = options.rig;
    const int w = rig.width_px, h = rig.height_px;
    const std::size_t count = static_cast<std::size_t>(w) * h;
    const Rgb8 sky = class_colour(23, "sky");
    frame.semantic = ImageRgb8{w, h, std::vector<std::uint8_t>(count * 3)};
    frame.instance = ImageU16{w, h, std::vector<std::uint16_t>(count, 0)};
    frame.disparity = ImageU16{w, h, std::vector<std::uint16_t>(count, 0)};
    frame.depth_mm = ImageU16{w, h, std::vector<std::uint16_t>(count, 0)};
    frame.depth_m.assign(count, 0.0f);
    const std::vector<float> disparity = disparity_from_window_depth(
        window_depth, rig.fx_px, rig.baseline_m, options.near_m, options.far_m);
    for (std::size_t i = 0; i < count; ++i) {
        const std::uint8_t* s = &semantic.pixels[i * 4];
        const bool drawn = s[3] != 0;
        for (int c = 0; c < 3; ++c) frame.semantic.pixels[i * 3 + c] = drawn ? s[c] : sky[c];
        const std::uint8_t* id = &instance.pixels[i * 4];
        if (id[3] != 0) frame.instance.values[i] = static_cast<std::uint16_t>(id[0] << 8 | id[1]);
        if (disparity[i] > 0.0f) {
            const double z = rig.fx_px * rig.baseline_m / static_cast<double>(disparity[i]);
            frame.depth_m[i] = static_cast<float>(z);
            frame.disparity.values[i] = static_cast<std::uint16_t>(
                std::min(65535L, std::lround(static_cast<double>(disparity[i]) * 256.0)));
            const long mm = std::lround(z * 1000.0);
            frame.depth_mm.values[i] = mm <= 65535 ? static_cast<std::uint16_t>(mm) : 0;
        }
    }
}

/// `o` seeing three times as far to each side at the same image size: the image is the centre
/// tile of a 3 x 3 grid (pixel u of the image is 3 u' - width of this one, u' in its tile).
RenderOptions wide_view(const RenderOptions& o) {
    RenderOptions wide = o;
    auto& k = *wide.view.intrinsics;
    k.fx_px /= 3.0;
    k.fy_px /= 3.0;
    k.cx_px = (k.cx_px + o.width_px) / 3.0;
    k.cy_px = (k.cy_px + o.height_px) / 3.0;
    return wide;
}

/// Share of the covered pixels of `solo` (rendered with wide_view) in its centre tile: the share
/// of the object inside the image, KITTI's 1 - truncation; 0 when nothing is covered.
double in_view_fraction(const ImageRgba8& solo) {
    const int w = solo.width;
    const int h = solo.height;
    std::size_t all = 0;
    std::size_t inside = 0;
    for (int v = 0; v < h; ++v) {
        for (int u = 0; u < w; ++u) {
            if (solo.pixels[(static_cast<std::size_t>(v) * w + u) * 4 + 3] == 0) continue;
            ++all;
            inside += 3 * u >= w && 3 * u < 2 * w && 3 * v >= h && 3 * v < 2 * h;
        }
    }
    return all == 0 ? 0.0 : static_cast<double>(inside) / static_cast<double>(all);
}

/// Visibility of every thing entity: its pixels in the instance image, alone (rendered with
/// `o`, instance shading), and the share of it inside the image (alone, seen wider).
void add_visibility(StereoFrame& frame, SceneRenderer& renderer,
                    const scene_schema::EntityDocument& document,
                    const scene_schema::EntityDocument& scene, const RenderOptions& o) {
    const RenderOptions wide = wide_view(o);
    const std::size_t count = frame.instance.values.size();
    std::vector<int> class_ids;
    for (const auto& e : scene.entities) class_ids.push_back(e.class_id);
    const std::vector<std::uint16_t> ids = kitti_instance_ids(class_ids);
    std::map<std::uint16_t, std::size_t> visible;
    for (const std::uint16_t v : frame.instance.values) ++visible[v];
    for (std::size_t e = 0; e < document.entities.size(); ++e) {
        const auto& entity = document.entities[e];
        if (!has_instances(entity.class_id)) continue;
        scene_schema::EntityDocument alone = document;
        alone.entities = {entity};
        const ImageRgba8 solo = renderer.render(alone, nullptr, o);
        EntityVisibility record;
        record.id = entity.id;
        record.class_name = entity.class_name;
        record.class_id = entity.class_id;
        record.instance = ids[e];
        record.visible_px = visible[ids[e]];
        for (std::size_t i = 0; i < count; ++i) record.unoccluded_px += solo.pixels[i * 4 + 3] != 0;
        record.in_view_fraction = in_view_fraction(renderer.render(alone, nullptr, wide));
        frame.visibility.push_back(record);
    }
}

}  // namespace

StereoFrame render_stereo_frame(SceneRenderer& renderer,
                                const scene_schema::EntityDocument& document,
                                const SensorOptions& options) {
    options.validate();
    const StereoRig& rig = options.rig;
    const scene_schema::EntityDocument scene = scene_with_underlay(document, options);
    RenderOptions o = rig_render_options(options);
    if (document.frame.pose) {
        // A drive's frame: the texture stays fixed in the drive's world. GL world = G X_kitti
        // with G = gl_from_kitti() its own inverse, so world_GL = G T_world_camera G frame_GL.
        o.texture_frame =
            gl_from_kitti() * glm::mat4(kitti_pose_matrix(*document.frame.pose)) * gl_from_kitti();
    }

    StereoFrame frame;
    frame.rig = rig;
    o.shading = Shading::lit;
    const ImageRgba8 left = renderer.render(scene, nullptr, o);
    o.view.camera_position_kitti = {static_cast<float>(rig.baseline_m), 0.0f, 0.0f};
    const ImageRgba8 right = renderer.render(scene, nullptr, o);
    o.view.camera_position_kitti = glm::vec3(0.0f);
    frame.left = apply_sensor_model(composite_sky(left, rig.cy_px), 0, options.sensor);
    frame.right = apply_sensor_model(composite_sky(right, rig.cy_px), 1, options.sensor);

    o.shading = Shading::semantic;
    const ImageRgba8 semantic = renderer.render(scene, nullptr, o);
    const std::vector<float> window_depth = renderer.read_depth();
    o.shading = Shading::instance;
    const ImageRgba8 instance = renderer.render(scene, nullptr, o);
    fill_ground_truth(frame, semantic, instance, window_depth, options);
    if (options.label_bleed_px > 0) {
        frame.semantic = apply_label_bleed(frame.semantic, frame.instance, options.label_bleed_px,
                                           options.sensor.seed);
    }
    add_visibility(frame, renderer, document, scene, o);
    return frame;
}

}  // namespace scene_viewer
