#include "cloud_analysis/pipeline/rig_fit.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>

#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>

#include "cloud_analysis/io/mat_view.hpp"
#include "stereoscene/support/number_text.hpp"

namespace cloud_analysis {
namespace {

using stereoscene::support::fixed_text;

/// The disparity range may stop this share short of the minimum depth (a range is a multiple
/// of 16 disparities).
constexpr double kDepthTolerance = 0.1;

/// Largest range of the census matcher at the matched resolution (DisparityOptions::validate).
constexpr int kSgmMaxDisparities = 256;

/// A length in pixels at another scale: at least 1 when it was (0 stays 0, off).
int scaled_length(int px, double scale) {
    if (px <= 0) return px;
    return std::max(1, static_cast<int>(std::lround(px * scale)));
}

/// A pixel count at another scale (an area: times scale^2), at least 1 when it was.
int scaled_count(int count, double scale) {
    if (count <= 0) return count;
    return std::max(1, static_cast<int>(std::lround(count * scale * scale)));
}

/// Labels (or ids) halved by the top-left pixel of each 2x2 block: no blending of classes.
template <typename T>
std::vector<T> pick_top_left(const std::vector<T>& src, int width, int channels, int out_width,
                             int out_height) {
    std::vector<T> out(static_cast<std::size_t>(out_width) * out_height * channels);
    for (int v = 0; v < out_height; ++v) {
        const T* row = src.data() + static_cast<std::size_t>(2 * v) * width * channels;
        T* dst = out.data() + static_cast<std::size_t>(v) * out_width * channels;
        for (int u = 0; u < out_width; ++u) {
            for (int c = 0; c < channels; ++c) dst[u * channels + c] = row[2 * u * channels + c];
        }
    }
    return out;
}

ImageU8 halve_by_area(const ImageU8& img) {
    ImageU8 out;
    out.width_px = img.width_px / 2;
    out.height_px = img.height_px / 2;
    out.channels = img.channels;
    out.data.resize(static_cast<std::size_t>(out.width_px) * out.height_px * out.channels);
    const cv::Mat src = mat_view(img);
    cv::Mat dst(out.height_px, out.width_px, CV_8UC(out.channels), out.data.data());
    cv::resize(src(cv::Rect(0, 0, 2 * out.width_px, 2 * out.height_px)), dst, dst.size(), 0, 0,
               cv::INTER_AREA);
    return out;
}

ImageU8 halve_labels(const ImageU8& img) {
    if (img.empty()) return img;
    ImageU8 out;
    out.width_px = img.width_px / 2;
    out.height_px = img.height_px / 2;
    out.channels = img.channels;
    out.data = pick_top_left(img.data, img.width_px, img.channels, out.width_px, out.height_px);
    return out;
}

}  // namespace

void RigOptions::validate() const {
    if (!(min_depth_m >= 0.0) || !std::isfinite(min_depth_m)) {
        throw std::invalid_argument("min_depth_m: must be >= 0 and finite");
    }
    if (half_resolution_above_px < 0) {
        throw std::invalid_argument("half_resolution_above_px: must be >= 0");
    }
    for (const auto& field : given) {
        if (field != "num_disparities" && rig_scaled_fields().count(field) == 0) {
            throw std::invalid_argument("rig.given: no such setting: " + field);
        }
    }
}

const std::set<std::string>& rig_scaled_fields() {
    static const std::set<std::string> fields = {
        // reprojection
        "depth_edge_rows",
        // stereo-only segmentation
        "column_bin_px", "min_cell_pixels", "green_window_px", "blend_rows", "edge_step_px",
        // entity extraction and the class config's per-class minimum
        "image_radius_px", "shadow_radius_px", "min_width_px", "strip_beside_width_px",
        "min_points", "point_lattice_px"};
    return fields;
}

double disparity_at_depth(const StereoCamera& c, double depth_m) {
    return c.fx_px * c.baseline_m / depth_m - (c.cx_right_px - c.cx_px);
}

double depth_at_disparity(const StereoCamera& c, double disparity_px) {
    const double d = disparity_px + (c.cx_right_px - c.cx_px);
    return d > 0.0 ? c.fx_px * c.baseline_m / d : std::numeric_limits<double>::infinity();
}

RigFit fit_to_rig(const AnalyseOptions& analyse, const ExtractOptions& extract,
                  const StereoCamera& camera) {
    RigFit fit;
    fit.analyse = analyse;
    fit.extract = extract;
    const RigOptions& rig = analyse.rig;
    const auto given = [&](const char* field) { return rig.given.count(field) > 0; };
    DisparityOptions& d = fit.analyse.disparity;

    // The range reaches within kDepthTolerance of the minimum depth: KITTI's 128 disparities
    // reach 3.03 m for a 3 m minimum.
    const double reach_m = rig.min_depth_m * (1.0 + kDepthTolerance);
    if (rig.min_depth_m > 0.0 && !given("num_disparities")) {
        // The smallest multiple of 16 whose last disparity is the one at reach_m.
        const double needed = disparity_at_depth(camera, reach_m) + 1.0 - d.min_disparity;
        const int maximum =
            d.matcher == "sgm" ? kSgmMaxDisparities * d.downscale : kMaxDisparityRange;
        const int steps = static_cast<int>(std::ceil(needed / 16.0));
        d.num_disparities = std::clamp(16 * steps, 16, maximum / 16 * 16);
        fit.range_from_min_depth = true;
    }
    fit.nearest_depth_m = depth_at_disparity(camera, d.min_disparity + d.num_disparities - 1);
    if (rig.min_depth_m > 0.0 && fit.nearest_depth_m > reach_m) {
        const int needed = static_cast<int>(std::ceil(disparity_at_depth(camera, reach_m))) + 1;
        fit.warnings.push_back(
            std::to_string(d.num_disparities) + " disparities reach " +
            fixed_text(fit.nearest_depth_m, 1) + " m on this rig (fx B = " +
            std::to_string(static_cast<int>(std::lround(camera.fx_px * camera.baseline_m))) +
            " px m): nearer surfaces cannot be matched; --min-depth " +
            fixed_text(rig.min_depth_m, 1) + " m needs about " + std::to_string(needed) +
            (fit.range_from_min_depth ? ", more than the matcher takes" : " (--num-disparities)"));
    }

    if (rig.scale_pixel_settings && camera.fx_px > 0.0) {
        const double s = camera.fx_px / kReferenceFocalPx;
        fit.scale = s;
        auto& r = fit.analyse.reproject;
        if (!given("depth_edge_rows")) r.depth_edge_rows = scaled_length(r.depth_edge_rows, s);
        auto& g = fit.analyse.geometry;
        if (!given("column_bin_px")) g.column_bin_px = scaled_length(g.column_bin_px, s);
        if (!given("min_cell_pixels")) g.min_cell_pixels = scaled_count(g.min_cell_pixels, s);
        if (!given("green_window_px")) g.green_window_px = scaled_length(g.green_window_px, s);
        if (!given("blend_rows")) g.blend_rows = scaled_length(g.blend_rows, s);
        if (!given("edge_step_px")) g.edge_step_px = scaled_length(g.edge_step_px, s);
        auto& e = fit.extract;
        if (!given("image_radius_px")) e.image_radius_px = scaled_length(e.image_radius_px, s);
        if (!given("shadow_radius_px")) e.shadow_radius_px = scaled_length(e.shadow_radius_px, s);
        if (!given("min_width_px")) e.min_width_px *= s;
        if (!given("strip_beside_width_px")) e.strip_beside_width_px *= s;
        // Things are taken on a lattice of the largest power-of-two step (at most 8) that
        // keeps at least the reference rig's pixels on an object: its points count n^2 pixels.
        if (!given("point_lattice_px")) {
            e.point_lattice_px = 1;
            while (2 * e.point_lattice_px <= std::min(8.0, s)) e.point_lattice_px *= 2;
        }
        if (!given("min_points")) {
            const auto scaled = [&](const ClassSettings& c) {
                return scaled_count(c.min_points, c.thing ? s / e.point_lattice_px : s);
            };
            e.classes.fallback.min_points = scaled(e.classes.fallback);
            for (auto& c : e.classes.classes) c.min_points = scaled(c);
        }
    }
    check_range_fits(camera.width_px, d);
    fit.analyse.validate();
    fit.extract.validate();
    return fit;
}

nlohmann::json RigFit::describe(const LoadedInputs& in) const {
    const DisparityOptions& d = analyse.disparity;
    nlohmann::json j;
    j["reference_fx"] = kReferenceFocalPx;
    j["scale"] = scale;
    j["point_lattice_px"] = extract.point_lattice_px;
    j["min_depth_m"] = analyse.rig.min_depth_m;
    j["num_disparities"] = d.num_disparities;
    j["num_disparities_from"] = range_from_min_depth ? "min_depth" : "given";
    j["nearest_depth_m"] = nearest_depth_m;
    j["resolution_scale"] = in.resolution_scale;
    j["read_size"] = {in.read_width_px, in.read_height_px};
    j["analysed_size"] = {in.left.width_px, in.left.height_px};
    return j;
}

AnalyseOptions RigFit::run_options(const Palette& palette, bool clouds) const {
    AnalyseOptions options = analyse;
    if (!clouds) options.class_points_only = class_selection(palette, extract);
    return options;
}

RunSettings RigFit::run_settings(RunSettings base, const LoadedInputs& inputs) const {
    base.analyse = analyse;
    base.rig = describe(inputs);
    return base;
}

void halve_inputs(LoadedInputs& in) {
    in.left = halve_by_area(in.left);
    in.right = halve_by_area(in.right);
    in.semantic = halve_labels(in.semantic);
    if (in.instance.has_ids()) {
        ImageU16& ids = in.instance.ids;
        const int w = ids.width_px / 2;
        const int h = ids.height_px / 2;
        ids.values = pick_top_left(ids.values, ids.width_px, 1, w, h);
        ids.width_px = w;
        ids.height_px = h;
    } else {
        in.instance.colour = halve_labels(in.instance.colour);
    }
    // Pixel u of the halved image covers u' = 2u and 2u + 1: its centre is 2u + 0.5.
    StereoCamera& c = in.calibration.camera;
    c.fx_px /= 2.0;
    c.fy_px /= 2.0;
    c.cx_px = (c.cx_px - 0.5) / 2.0;
    c.cx_right_px = (c.cx_right_px - 0.5) / 2.0;
    c.cy_px = (c.cy_px - 0.5) / 2.0;
    c.width_px = in.left.width_px;
    c.height_px = in.left.height_px;
    in.resolution_scale *= 0.5;
}

}  // namespace cloud_analysis
