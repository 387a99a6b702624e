#pragma once

/// Synthetic stereo sensors: what a rectified stereo rig sees of a known scene. The
/// left and right colour images (world-fixed procedural texture, sky, light, then a seeded sensor
/// model), the semantic and KITTI instance images, ground-truth disparity and depth of the left
/// view, and the rig's calibration in KITTI's calib_cam_to_cam.txt form. Like CARLA's
/// ground-truth pseudo-sensors (Dosovitskiy et al., CARLA, CoRL 2017).

#include <cstdint>
#include <filesystem>
#include <map>
#include <string>
#include <vector>

#include "scene_schema/entities.hpp"

namespace scene_viewer {

class SceneRenderer;

/// An 8-bit RGB image, rows top to bottom.
struct ImageRgb8 {
    int width = 0;
    int height = 0;
    std::vector<std::uint8_t> pixels;  ///< width * height * 3 bytes
};

/// A 16-bit single-channel image, rows top to bottom.
struct ImageU16 {
    int width = 0;
    int height = 0;
    std::vector<std::uint16_t> values;  ///< width * height values
};

/// A rectified stereo rig: the left camera is the entity file's frame, the right camera is the
/// left one translated by +baseline_m along x. KITTI's by default (object benchmark, P2/P3).
struct StereoRig {
    int width_px = 1242;            ///< image width, pixels
    int height_px = 375;            ///< image height, pixels
    double fx_px = 721.5377;        ///< focal length along x, pixels
    double fy_px = 721.5377;        ///< focal length along y, pixels
    double cx_px = 609.5593;        ///< principal point x, pixels
    double cy_px = 172.854;         ///< principal point y, pixels
    double baseline_m = 0.54;       ///< distance between the optical centres, metres
    double camera_height_m = 1.65;  ///< camera above the road (ground underlay), metres
    /// Throws std::invalid_argument naming the bad field.
    void validate() const;
    /// The same rig at another image size: intrinsics scale with the size.
    StereoRig resized(int width_px, int height_px) const;
};

/// Names of the rig presets (rig_preset).
const std::vector<std::string>& rig_preset_names();

/// A named rig's image size, intrinsics and baseline, the camera height kept from `base` (the
/// scene's): "kitti" (1242x375, fx 721.5, 0.54 m), "cityscapes" (2048x1024, fx 2262.5,
/// 0.209 m), "argoverse" (a 5 MP rig like Argoverse's stereo pair: 2464x2056, fx 3894,
/// 0.30 m), "zed" (a ZED-like 720p rig: 1280x720, fx 700, 0.12 m) and "realsense" (a
/// RealSense D435-like 720p rig: 1280x720, fx 640, 0.05 m). Throws std::invalid_argument for
/// another name.
StereoRig rig_preset(const std::string& name, const StereoRig& base);

/// The rig for a document: `defaults`, with the intrinsics (and baseline, when > 0) of the file's
/// frame.camera when present.
StereoRig rig_for(const scene_schema::EntityDocument& document, const StereoRig& defaults);

/// The seeded sensor model applied to the rendered colour images.
struct SensorModelOptions {
    std::uint64_t seed = 0;            ///< seed of the noise; same seed, same bytes
    double noise_sigma = 2.0;          ///< Gaussian noise, standard deviation, 8-bit levels, >= 0
    double blur_sigma_px = 0.5;        ///< Gaussian blur, standard deviation, pixels, 0 = none
    double right_gain = 0.93;          ///< right camera gain relative to the left (> 0)
    bool vignetting = false;           ///< darken towards the corners
    double vignetting_strength = 0.3;  ///< share of light lost in the corners, 0..1
    /// Throws std::invalid_argument naming the bad field.
    void validate() const;
};

/// Everything that drives one sensor render.
struct SensorOptions {
    StereoRig rig;                 ///< cameras
    SensorModelOptions sensor;     ///< noise, blur, gain, vignetting
    int msaa_samples = 4;          ///< colour images: multisample count, 0 = off
    bool ground_underlay = true;   ///< terrain plane 1 cm under the road level (no holes to sky)
    double underlay_size_m = 300;  ///< side of the underlay square, metres
    float near_m = 0.3f;           ///< near plane, metres (depth precision)
    float far_m = 1000.0f;         ///< far plane, metres
    int label_bleed_px = 0;        ///< semantic image: thing borders moved out or in by up to
                                   ///< this many pixels (seeded, apply_label_bleed), 0..16
    bool vehicle_paints = false;   ///< colour images: vehicles in the world's car paints
                                   ///< (RenderOptions::vehicle_paints), not the class colour
    /// Throws std::invalid_argument naming the bad field.
    void validate() const;
};

/// How much of one thing entity (a class with instances) the left camera sees: its pixels in
/// the instance image, and its pixels when rendered alone (no occluders, same camera; pixels
/// outside the image count in neither, so truncation is not occlusion).
struct EntityVisibility {
    std::string id;                 ///< entity id in the scene file
    std::string class_name;         ///< class name in the scene file
    int class_id = 0;               ///< Cityscapes labelId
    std::uint16_t instance = 0;     ///< its value in the instance image (labelId << 8 | n)
    std::size_t visible_px = 0;     ///< pixels in the instance image
    std::size_t unoccluded_px = 0;  ///< pixels when rendered alone
    /// Share of it inside the image when rendered alone on an image plane three times as wide
    /// and high (KITTI's 1 - truncation): 1 when it lies wholly in the image.
    double in_view_fraction = 1.0;
    /// Share of the object the camera sees: in_view_fraction * visible_px / unoccluded_px (0
    /// when it is not in the image at all), hidden by other objects or cut by the image border.
    double visible_fraction() const;
};

/// One frame of the synthetic rig.
struct StereoFrame {
    StereoRig rig;               ///< the rig that saw it
    ImageRgb8 left;              ///< left colour image after the sensor model
    ImageRgb8 right;             ///< right colour image after the sensor model
    ImageRgb8 semantic;          ///< Cityscapes colours of the left view, sky 70,130,180
    ImageU16 instance;           ///< KITTI instance ids of the left view (labelId << 8 | n), 0 none
    ImageU16 disparity;          ///< KITTI disparity of the left view: round(d * 256), 0 none
    ImageU16 depth_mm;           ///< left view depth (z), millimetres, 0 none or beyond 65.535 m
    std::vector<float> depth_m;  ///< left view depth (z), metres, 0 where nothing was drawn
    std::vector<EntityVisibility> visibility;  ///< every thing entity, in file order
};

/// Renders the rig's view of `document` with `renderer` (class models already set), plus one
/// instance render of every thing entity alone for its visibility. The renderer's loaded world
/// is replaced.
StereoFrame render_stereo_frame(SceneRenderer& renderer,
                                const scene_schema::EntityDocument& document,
                                const SensorOptions& options);

/// Disparity of a pinhole rig from window depth: linearises the perspective depth
/// (z = 2 n f / (f + n - (2 d - 1)(f - n))) and returns fx * B / z; 0 where depth is 1.
std::vector<float> disparity_from_window_depth(const std::vector<float>& window_depth, double fx_px,
                                               double baseline_m, float near_m, float far_m);

/// Applies the sensor model to one camera's image: blur, gain, vignetting, Gaussian noise.
/// `camera` (0 left, 1 right) picks the noise stream and the gain.
ImageRgb8 apply_sensor_model(const ImageRgb8& image, int camera, const SensorModelOptions& options);

/// The semantic image with label bleed at the borders of things (instance labelIds 24-33), as
/// hand-drawn polygon labels have (KITTI's semantic and instance images): a seeded field of
/// offsets in -max_px..max_px, smooth over 16 px cells, grows a thing into the pixels around it
/// (offset > 0: a pixel outside every thing takes the colour of the nearest thing pixel within
/// the offset) or shrinks it (offset < 0: a thing pixel takes the colour of the nearest pixel of
/// anything else within the offset). The instance image is the truth and is not changed.
ImageRgb8 apply_label_bleed(const ImageRgb8& semantic, const ImageU16& instance, int max_px,
                            std::uint64_t seed);

/// KITTI calib_cam_to_cam.txt text for the rig: cameras 02 (left) and 03 (right), S_rect,
/// R_rect identity, P_rect with -fx * B in P_rect_03[0, 3] (KITTI devkit readme).
std::string format_kitti_calib(const StereoRig& rig);

/// Reads the rig back from calib_cam_to_cam.txt text (P_rect_02, P_rect_03, S_rect_02); throws
/// std::invalid_argument naming the missing or bad key. camera_height_m keeps its default.
StereoRig parse_kitti_calib(const std::string& text);

/// PNG bytes (zlib) of an 8-bit RGB or 16-bit grey image.
std::vector<unsigned char> encode_png_rgb8(const ImageRgb8& image);
std::vector<unsigned char> encode_png_u16(const ImageU16& image);

/// Throws std::invalid_argument unless `frame_name` is a plain file stem (no folders).
void check_frame_name(const std::string& frame_name);

/// JSON text of a frame's visibility records (docs/sensors.md "Visibility"): the image size
/// and, per thing entity, id, class, class_id, instance, visible_px, unoccluded_px and
/// visible_fraction (4 decimals).
std::string format_visibility_json(const StereoFrame& frame);

/// The files of a frame in a KITTI-like layout, relative path -> bytes: image_2/F.png,
/// image_3/F.png, semantic_rgb/F.png, instance/F.png, disp_occ_0/F.png, depth/F.png (uint16
/// millimetres), visibility/F.json, calib/calib_cam_to_cam.txt.
std::map<std::string, std::string> kitti_layout_files(const StereoFrame& frame,
                                                      const std::string& frame_name);

/// The relative paths kitti_layout_files writes for a frame, in the same order.
std::vector<std::string> kitti_layout_names(const std::string& frame_name);

/// Whether every file of `relative` exists under `root` as a regular file (written whole: each
/// is renamed into place), after removing the temporary and backup files a killed writer left
/// beside them (`.NAME.tmp-*`, `.NAME.old-*`, support::OutputTransaction).
bool files_complete(const std::filesystem::path& root, const std::vector<std::string>& relative);

/// Writes every file of `files` under `root` as one support::OutputTransaction: all of them or
/// none, earlier files restored on failure, folders created as needed and removed again when
/// the write fails. A relative path that is absolute or climbs out of `root` is refused.
/// Throws support::FileError.
void write_files(const std::filesystem::path& root,
                 const std::map<std::string, std::string>& files);

}  // namespace scene_viewer
