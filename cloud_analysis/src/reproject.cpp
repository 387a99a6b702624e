#include "cloud_analysis/reproject.hpp"

#include <cmath>
#include <stdexcept>
#include <vector>

#include "cloud_analysis/calibration.hpp"

namespace cloud_analysis {

void ReprojectOptions::validate() const {
    if (!(max_range_m > 0.0)) throw std::invalid_argument("max_range_m: must be > 0");
    if (!(min_disparity_px >= 0.0)) throw std::invalid_argument("min_disparity_px: must be >= 0");
}

LabeledCloud reproject(const DisparityMap& disparity, const StereoCamera& camera,
                       const ImageU8& left, const ClassImage& classes,
                       const ReprojectOptions& options) {
    options.validate();
    const int w = disparity.width_px;
    const int h = disparity.height_px;
    if (left.width_px != w || left.height_px != h) {
        throw std::invalid_argument("left image and disparity differ in size");
    }
    const bool labelled = !classes.class_index.empty();
    if (labelled && (classes.width_px != w || classes.height_px != h)) {
        throw std::invalid_argument("semantic image and disparity differ in size");
    }
    if (!(camera.baseline_m > 0.0) || !(camera.fx_px > 0.0) || !(camera.fy_px > 0.0)) {
        throw std::invalid_argument("camera: fx, fy and baseline must be > 0");
    }
    // (X, Y, Z, W) = Q (u, v, d, 1) with OpenCV's Q (reprojection_matrix): X = u - cx,
    // Y = (v - cy) fx / fy, Z = fx, W = (d - (cx - cx_right)) / B. Only W depends on d, so the
    // 4x4 product reduces to one reciprocal per point; rows and columns are precomputed.
    const Eigen::Matrix4d Q = reprojection_matrix(camera);
    const double w_per_px = Q(3, 2);
    const double w_offset = Q(3, 3);
    const double z_num = Q(2, 3);
    std::vector<double> x_num(static_cast<std::size_t>(w));
    for (int u = 0; u < w; ++u) x_num[static_cast<std::size_t>(u)] = Q(0, 0) * u + Q(0, 3);
    const double max_range_sq = options.max_range_m * options.max_range_m;
    const double min_d = options.min_disparity_px;

    // Written through raw pointers into arrays sized for every valid pixel, trimmed at the end:
    // no per-point capacity checks.
    LabeledCloud cloud;
    cloud.width_px = w;
    cloud.height_px = h;
    const std::size_t capacity = disparity.valid_count();
    cloud.xyz_m.resize(capacity);
    cloud.colour.resize(capacity);
    cloud.class_index.resize(capacity);
    cloud.pixel.resize(capacity);
    Eigen::Vector3f* xyz = cloud.xyz_m.data();
    Rgb* colour = cloud.colour.data();
    std::uint16_t* cls_out = cloud.class_index.data();
    std::uint32_t* pixel = cloud.pixel.data();
    std::size_t n = 0;
    const bool grey = left.channels != 3;
    for (int v = 0; v < h; ++v) {
        const std::size_t row = static_cast<std::size_t>(v) * static_cast<std::size_t>(w);
        const float* d_row = disparity.disparity_px.data() + row;
        const std::uint16_t* c_row = labelled ? classes.class_index.data() + row : nullptr;
        const std::uint8_t* img_row =
            left.data.data() + row * static_cast<std::size_t>(left.channels);
        const double y_num = Q(1, 1) * v + Q(1, 3);
        for (int u = 0; u < w; ++u) {
            const double d = d_row[u];
            if (!(d > min_d)) continue;
            const std::uint16_t cls = labelled ? c_row[u] : kVoidClass;
            if (cls == kVoidClass && !options.keep_void) continue;
            const double w_h = w_per_px * d + w_offset;
            if (!(w_h > 0.0)) continue;  // at or beyond infinity
            const double inv = 1.0 / w_h;
            const double x = x_num[static_cast<std::size_t>(u)] * inv;
            const double y = y_num * inv;
            const double z = z_num * inv;
            if (!(x * x + y * y + z * z <= max_range_sq)) continue;
            xyz[n] = Eigen::Vector3f(static_cast<float>(x), static_cast<float>(y),
                                     static_cast<float>(z));
            const std::uint8_t* c = grey ? img_row + u : img_row + 3 * static_cast<std::size_t>(u);
            colour[n] = grey ? Rgb{c[0], c[0], c[0]} : Rgb{c[0], c[1], c[2]};
            cls_out[n] = cls;
            pixel[n] = static_cast<std::uint32_t>(row + static_cast<std::size_t>(u));
            ++n;
        }
    }
    cloud.xyz_m.resize(n);
    cloud.colour.resize(n);
    cloud.class_index.resize(n);
    cloud.pixel.resize(n);
    return cloud;
}

}  // namespace cloud_analysis
