#include "cloud_analysis/reproject.hpp"

#include <cmath>
#include <stdexcept>

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
    const Eigen::Matrix4d Q = reprojection_matrix(camera);
    const double max_range_sq = options.max_range_m * options.max_range_m;

    LabeledCloud cloud;
    cloud.width_px = w;
    cloud.height_px = h;
    const std::size_t capacity = disparity.valid_count();
    cloud.xyz_m.reserve(capacity);
    cloud.colour.reserve(capacity);
    cloud.class_index.reserve(capacity);
    cloud.pixel.reserve(capacity);
    for (int v = 0; v < h; ++v) {
        const std::size_t row = static_cast<std::size_t>(v) * w;
        for (int u = 0; u < w; ++u) {
            const std::size_t i = row + static_cast<std::size_t>(u);
            const double d = disparity.disparity_px[i];
            if (!(d > options.min_disparity_px)) continue;
            const std::uint16_t cls = labelled ? classes.class_index[i] : kVoidClass;
            if (cls == kVoidClass && !options.keep_void) continue;
            // (X, Y, Z, W) = Q (u, v, d, 1)
            const Eigen::Vector4d p = Q * Eigen::Vector4d(u, v, d, 1.0);
            if (!(p[3] > 0.0)) continue;  // at or beyond infinity
            const Eigen::Vector3d xyz = p.head<3>() / p[3];
            if (!(xyz.squaredNorm() <= max_range_sq)) continue;
            cloud.xyz_m.push_back(xyz.cast<float>());
            const std::uint8_t* c = left.at(u, v);
            cloud.colour.push_back(left.channels == 3 ? Rgb{c[0], c[1], c[2]}
                                                      : Rgb{c[0], c[0], c[0]});
            cloud.class_index.push_back(cls);
            cloud.pixel.push_back(static_cast<std::uint32_t>(i));
        }
    }
    return cloud;
}

}  // namespace cloud_analysis
