#include "cloud_analysis/pipeline/pipeline.hpp"

#include <chrono>
#include <future>
#include <stdexcept>

#include "cloud_analysis/pipeline/rig_fit.hpp"
#include "stereoscene/support/limits.hpp"

namespace cloud_analysis {
namespace {

std::string size_text(const ImageU8& img) {
    return std::to_string(img.width_px) + "x" + std::to_string(img.height_px);
}

class Stopwatch {
  public:
    explicit Stopwatch(std::vector<StageTiming>& out) : out_(out) {}
    void lap(const std::string& stage) {
        const auto now = std::chrono::steady_clock::now();
        out_.push_back({stage, std::chrono::duration<double, std::milli>(now - start_).count()});
        start_ = now;
    }

  private:
    std::vector<StageTiming>& out_;
    std::chrono::steady_clock::time_point start_ = std::chrono::steady_clock::now();
};

/// Reads the instance image of `in` and checks it against the other inputs.
void load_instance(LoadedInputs& in, const AnalyseOptions& options) {
    const std::string at = " (" + in.paths.instance.string() + ")";
    if (in.semantic.empty() || options.semantics == "geometry") {
        throw std::runtime_error(
            "cannot use instance image: instances need the semantic image's classes (--semantic, "
            "not --semantics geometry)" +
            at);
    }
    if (options.raw) {
        throw std::runtime_error(
            "cannot use instance image: it is not rectified with --raw (give rectified images)" +
            at);
    }
    in.instance = read_id_image(in.paths.instance);
    if (in.instance.width_px() != in.left.width_px ||
        in.instance.height_px() != in.left.height_px) {
        throw std::runtime_error("inputs do not match: instance image is " +
                                 std::to_string(in.instance.width_px()) + "x" +
                                 std::to_string(in.instance.height_px()) + ", left image is " +
                                 size_text(in.left) + at);
    }
}

/// The per-pixel objects of the instance image of `in`, decoded against `classes`.
InstanceMap decode_instance_image(const LoadedInputs& in, const ClassImage& classes,
                                  const AnalyseOptions& options) {
    try {
        return decode_instances(in.instance, parse_instance_encoding(options.instance_encoding),
                                classes, in.palette);
    } catch (const std::invalid_argument& e) {
        throw std::runtime_error(std::string("cannot use instance image: ") + e.what() + " (" +
                                 in.paths.instance.string() + ")");
    }
}

/// The semantic image's classes and the instance image's objects.
struct Labels {
    ClassImage classes;
    InstanceMap instances;
};

}  // namespace

InputPaths kitti_layout(const std::filesystem::path& root, const std::string& frame) {
    InputPaths p;
    p.frame_id = frame;
    p.left = root / "image_2" / (frame + ".png");
    p.right = root / "image_3" / (frame + ".png");
    const auto semantic = root / "semantic_rgb" / (frame + ".png");
    if (std::filesystem::exists(semantic)) p.semantic = semantic;
    std::string stem = frame;
    if (const auto us = stem.find('_'); us != std::string::npos) stem.resize(us);
    for (const auto& candidate :
         {root / "calib" / (frame + ".txt"), root / "calib" / (stem + ".txt"),
          root / "calib" / "calib_cam_to_cam.txt"}) {
        if (std::filesystem::exists(candidate)) {
            p.calibration = candidate;
            break;
        }
    }
    if (p.calibration.empty()) p.calibration = root / "calib" / "calib_cam_to_cam.txt";
    return p;
}

std::filesystem::path kitti_instance_path(const std::filesystem::path& root,
                                          const std::string& frame) {
    return root / "instance" / (frame + ".png");
}

void AnalyseOptions::validate() const {
    if (palette.empty()) throw std::invalid_argument("palette: must not be empty");
    if (semantics != "labels" && semantics != "geometry" && semantics != "auto") {
        throw std::invalid_argument("semantics: must be labels, geometry or auto");
    }
    parse_instance_encoding(instance_encoding);
    geometry.validate();
    calibration.validate();
    disparity.validate();
    reproject.validate();
    rig.validate();
}

LoadedInputs load_inputs(const InputPaths& paths, const AnalyseOptions& options) {
    options.validate();
    const Calibration calibration = load_calibration(paths.calibration, options.calibration);
    const Palette palette = [&] {
        try {
            return load_palette(options.palette);
        } catch (const std::exception& e) {
            throw std::runtime_error(std::string("cannot read palette: ") + e.what());
        }
    }();
    return load_inputs(paths, options, calibration, palette);
}

LoadedInputs load_inputs(const InputPaths& paths, const AnalyseOptions& options,
                         const Calibration& calibration, const Palette& palette) {
    options.validate();
    LoadedInputs in;
    in.paths = paths;
    in.calibration = calibration;
    in.palette = palette;
    // The three decodes are independent: right and semantic on helper threads (halves the load
    // stage of a KITTI frame on 2 cores). Errors still surface in the order left, right, semantic.
    auto right = std::async(std::launch::async, [&] { return read_image(paths.right); });
    auto semantic = std::async(std::launch::async, [&] {
        return paths.semantic.empty() ? ImageU8{} : read_image(paths.semantic, ImageMode::kColour);
    });
    in.left = read_image(paths.left);
    in.right = right.get();
    if (in.left.width_px != in.right.width_px || in.left.height_px != in.right.height_px) {
        throw std::runtime_error("inputs do not match: right image is " + size_text(in.right) +
                                 ", left image is " + size_text(in.left) + " (" +
                                 paths.right.string() + ")");
    }
    if (in.left.channels != in.right.channels) {
        // Mixed grey/colour pairs are matched in grey.
        in.left = read_image(paths.left, ImageMode::kGrey);
        in.right = read_image(paths.right, ImageMode::kGrey);
    }
    in.semantic = semantic.get();
    if (!paths.instance.empty()) load_instance(in, options);
    if (!paths.semantic.empty()) {
        if (in.semantic.width_px != in.left.width_px ||
            in.semantic.height_px != in.left.height_px) {
            throw std::runtime_error("inputs do not match: semantic image is " +
                                     size_text(in.semantic) + ", left image is " +
                                     size_text(in.left) + " (" + paths.semantic.string() + ")");
        }
    }
    StereoCamera& cam = in.calibration.camera;
    if (options.raw) {
        if (!in.calibration.raw_left || !in.calibration.raw_right) {
            throw std::runtime_error(
                "cannot rectify: calibration has no K_0x/D_0x/R_rect_0x or distortion (" +
                paths.calibration.string() + ")");
        }
        // The rectified images are the calibration's size, not the inputs': refused up front
        // like any image over the limit, before the maps are built.
        if (cam.width_px > 0) {
            stereoscene::support::check_limit("rectified image of " + paths.calibration.string(),
                                              static_cast<std::uint64_t>(cam.width_px) *
                                                  static_cast<std::uint64_t>(cam.height_px),
                                              stereoscene::support::limits().max_image_pixels,
                                              "pixels", stereoscene::support::kPixelsHint);
        }
    } else if (cam.width_px > 0 &&
               (cam.width_px != in.left.width_px || cam.height_px != in.left.height_px)) {
        throw std::runtime_error("inputs do not match: calibration is for " +
                                 std::to_string(cam.width_px) + "x" +
                                 std::to_string(cam.height_px) + " images, left image is " +
                                 size_text(in.left) + " (" + paths.calibration.string() + ")");
    }
    if (cam.width_px == 0) {
        cam.width_px = in.left.width_px;
        cam.height_px = in.left.height_px;
    }
    in.read_width_px = in.left.width_px;
    in.read_height_px = in.left.height_px;
    const long long pixels = static_cast<long long>(in.left.width_px) * in.left.height_px;
    if (!options.raw && options.rig.half_resolution_above_px > 0 &&
        pixels > options.rig.half_resolution_above_px) {
        halve_inputs(in);
    }
    return in;
}

void check_range_fits(int width_px, const DisparityOptions& d) {
    if (width_px > 0 && width_px < d.num_disparities + d.block_size) {
        throw std::runtime_error("image too narrow: " + std::to_string(width_px) + " px for " +
                                 std::to_string(d.num_disparities) +
                                 " disparities (--num-disparities, --min-depth)");
    }
}

AnalyseResult analyse(const LoadedInputs& in, const AnalyseOptions& options) {
    DisparityMatcher matcher(options.disparity);
    return analyse(in, options, matcher);
}

AnalyseResult analyse(const LoadedInputs& in, const AnalyseOptions& options,
                      DisparityMatcher& matcher) {
    options.validate();
    AnalyseResult r;
    r.camera = in.calibration.camera;
    check_range_fits(r.camera.width_px, matcher.options());
    Stopwatch watch(r.timings);
    const ImageU8* left = &in.left;
    const ImageU8* right = &in.right;
    const ImageU8* semantic = &in.semantic;
    ImageU8 rect_left, rect_right, rect_semantic;
    if (options.raw) {
        rect_left = rectify_image(in.left, *in.calibration.raw_left, r.camera);
        rect_right = rectify_image(in.right, *in.calibration.raw_right, r.camera);
        if (!in.semantic.empty()) {
            rect_semantic = rectify_image(in.semantic, *in.calibration.raw_left, r.camera,
                                          /*nearest=*/true);
        }
        left = &rect_left;
        right = &rect_right;
        semantic = &rect_semantic;
        watch.lap("rectify");
    }
    // The class lookup does not depend on the disparity: it runs beside the matcher, and the
    // "semantic" lap below is only the wait for it.
    r.semantics = semantics_path(in, options);
    std::future<Labels> labels;
    if (r.semantics == "labels") {
        labels = std::async(std::launch::async, [semantic, &in, &options] {
            Labels l;
            l.classes = classify_pixels(*semantic, in.palette);
            if (in.instance.width_px() > 0)
                l.instances = decode_instance_image(in, l.classes, options);
            return l;
        });
    }
    r.disparity = matcher.compute(*left, *right);
    watch.lap("disparity");
    if (!r.disparity.any_valid()) {
        throw std::runtime_error("empty disparity: no pixel has a valid disparity (" +
                                 in.paths.left.string() + ")");
    }
    if (labels.valid()) {
        Labels l = labels.get();
        r.classes = std::move(l.classes);
        r.instances = std::move(l.instances);
    }
    if (r.semantics != "geometry") {
        watch.lap("semantic");
    } else {
        r.geometry =
            geometry::derive_semantics(r.disparity, r.camera, *left, in.palette, options.geometry);
        r.classes = std::move(r.geometry->classes);
        r.geometry->classes = ClassImage{};
        watch.lap("geometry");
    }
    if (options.class_points_only) {
        r.points = reproject_by_class(r.disparity, r.camera, r.classes, options.reproject,
                                      *options.class_points_only);
        r.cloud_points = r.points.cloud_points;
    } else {
        r.cloud = reproject(r.disparity, r.camera, *left, r.classes, options.reproject);
        r.cloud_points = r.cloud.size();
    }
    if (!r.instances.empty()) {
        const bool points = options.class_points_only.has_value();
        (points ? r.points.instance_id : r.cloud.instance_id) = r.instances.id;
        (points ? r.points.depth_m : r.cloud.depth_m) =
            depth_of(r.disparity, points ? r.points.border : r.cloud.border);
        mark_object_outlines(points ? r.points.depth_edge : r.cloud.depth_edge, r.instances,
                             r.disparity, points ? r.points.border : r.cloud.border,
                             options.reproject.depth_edge_step_m,
                             options.reproject.depth_edge_rows);
    }
    watch.lap("reproject");
    if (r.cloud_points == 0) {
        throw std::runtime_error("empty cloud: no point within " +
                                 std::to_string(options.reproject.max_range_m) +
                                 " m (--max-range)");
    }
    return r;
}

std::vector<std::string> analysis_warnings(const LoadedInputs& in, const AnalyseResult& r) {
    std::vector<std::string> out;
    if (in.resolution_scale != 1.0) {
        out.push_back("analysed at half resolution (" + size_text(in.left) + "): " +
                      std::to_string(in.read_width_px) + "x" + std::to_string(in.read_height_px) +
                      " is over --half-resolution-above pixels (" + in.paths.left.string() + ")");
    }
    if (r.geometry) {
        for (const auto& w : r.geometry->warnings) out.push_back(w);
    }
    if (r.semantics == "none") {
        out.push_back("no semantic image: every point is void");
    } else if (r.semantics == "labels" && r.classes.void_pixels > 0) {
        out.push_back(std::to_string(r.classes.void_pixels) +
                      " semantic pixels have colours not in palette '" + in.palette.name +
                      "' and count as void (" + in.paths.semantic.string() + ")");
    }
    return out;
}

std::string semantics_path(const LoadedInputs& in, const AnalyseOptions& o) {
    if (o.semantics == "geometry") return "geometry";
    if (!in.semantic.empty()) return "labels";
    return o.semantics == "auto" ? "geometry" : "none";
}

nlohmann::json describe_run(const LoadedInputs& in, const AnalyseOptions& o,
                            const std::string& tool_version) {
    const DisparityOptions& d = o.disparity;
    const StereoCamera& c = in.calibration.camera;
    nlohmann::json j;
    j["tool"] = "cloud-analysis";
    j["version"] = tool_version;
    j["inputs"] = {{"left", in.paths.left.string()},
                   {"right", in.paths.right.string()},
                   {"semantic", in.paths.semantic.string()},
                   {"instance", in.paths.instance.string()},
                   {"calibration", in.paths.calibration.string()}};
    j["calibration"] = {
        {"format", in.calibration.format},
        {"fx", c.fx_px},
        {"fy", c.fy_px},
        {"cx", c.cx_px},
        {"cy", c.cy_px},
        {"cx_right", c.cx_right_px},
        {"baseline_m", c.baseline_m},
        {"width", c.width_px},
        {"height", c.height_px},
        {"left_camera", o.calibration.left_camera},
        {"right_camera", o.calibration.right_camera},
        {"disparity_offset_px", o.calibration.disparity_offset_px},
        {"raw", o.raw},
        {"reference_offset_m",
         {in.calibration.reference_offset_m.x(), in.calibration.reference_offset_m.y(),
          in.calibration.reference_offset_m.z()}}};
    j["palette"] = in.palette.name;
    j["semantics"] = semantics_path(in, o);
    j["disparity"] = {{"min_disparity", d.min_disparity},
                      {"num_disparities", d.num_disparities},
                      {"block_size", d.block_size},
                      {"p1", d.p1},
                      {"p2", d.p2},
                      {"disp12_max_diff", d.disp12_max_diff},
                      {"pre_filter_cap", d.pre_filter_cap},
                      {"uniqueness_ratio", d.uniqueness_ratio},
                      {"speckle_window_size", d.speckle_window_size},
                      {"speckle_range", d.speckle_range},
                      {"mode", d.mode},
                      {"colour", d.colour},
                      {"pad_left", d.pad_left},
                      {"lr_check", d.lr_check},
                      {"lr_max_diff_px", d.lr_max_diff_px},
                      {"wls", d.wls},
                      {"wls_lambda", d.wls_lambda},
                      {"wls_sigma_colour", d.wls_sigma_colour},
                      {"downscale", d.downscale}};
    j["reproject"] = {{"max_range_m", o.reproject.max_range_m},
                      {"min_disparity_px", o.reproject.min_disparity_px},
                      {"keep_void", o.reproject.keep_void},
                      {"depth_edge_step_m", o.reproject.depth_edge_step_m},
                      {"depth_edge_rows", o.reproject.depth_edge_rows}};
    return j;
}

}  // namespace cloud_analysis
