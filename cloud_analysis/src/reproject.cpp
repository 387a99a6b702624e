#include "cloud_analysis/reproject.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <vector>

#include <opencv2/core.hpp>

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
    std::vector<double> x_num(static_cast<std::size_t>(w)), x_num_sq(x_num.size());
    for (int u = 0; u < w; ++u) {
        x_num[static_cast<std::size_t>(u)] = Q(0, 0) * u + Q(0, 3);
        x_num_sq[static_cast<std::size_t>(u)] =
            x_num[static_cast<std::size_t>(u)] * x_num[static_cast<std::size_t>(u)];
    }
    const double max_range_sq = options.max_range_m * options.max_range_m;
    const double min_d = options.min_disparity_px;
    const bool grey = left.channels != 3;
    const auto row_of = [w](int v) {
        return static_cast<std::size_t>(v) * static_cast<std::size_t>(w);
    };
    // Calls emit(u, w_h, class) for each pixel of row v that becomes a point, in order. The
    // range test needs no division: |(X, Y, Z)| / W <= r  <=>  |(X, Y, Z)|^2 <= r^2 W^2, W > 0.
    const auto for_each_point = [&](int v, auto&& emit) {
        const std::size_t row = row_of(v);
        const float* d_row = disparity.disparity_px.data() + row;
        const std::uint16_t* c_row = labelled ? classes.class_index.data() + row : nullptr;
        const double y_num = Q(1, 1) * v + Q(1, 3);
        const double yz_num_sq = y_num * y_num + z_num * z_num;
        for (int u = 0; u < w; ++u) {
            const double d = d_row[u];
            if (!(d > min_d)) continue;
            const std::uint16_t cls = labelled ? c_row[u] : kVoidClass;
            if (cls == kVoidClass && !options.keep_void) continue;
            const double w_h = w_per_px * d + w_offset;
            if (!(w_h > 0.0)) continue;  // at or beyond infinity
            if (!(x_num_sq[static_cast<std::size_t>(u)] + yz_num_sq <= max_range_sq * w_h * w_h)) {
                continue;
            }
            emit(u, y_num, w_h, cls);
        }
    };
    // Rows in parallel stripes, twice: the points of each row are counted, then written from
    // the row's offset (the same tests in the same order, so the counts hold): the cloud comes
    // out in pixel order, as from one pass.
    std::vector<std::size_t> offset(static_cast<std::size_t>(h) + 1, 0);
    const int stripes = std::max(1, std::min(h, 16));
    cv::parallel_for_(
        cv::Range(0, h),
        [&](const cv::Range& rows) {
            for (int v = rows.start; v < rows.end; ++v) {
                std::size_t n = 0;
                for_each_point(v, [&n](int, double, double, std::uint16_t) { ++n; });
                offset[static_cast<std::size_t>(v) + 1] = n;
            }
        },
        stripes);
    for (std::size_t v = 0; v < static_cast<std::size_t>(h); ++v) offset[v + 1] += offset[v];
    LabeledCloud cloud;
    cloud.width_px = w;
    cloud.height_px = h;
    const std::size_t n = offset.back();
    cloud.xyz_m.resize(n);
    cloud.colour.resize(n);
    cloud.class_index.resize(n);
    cloud.pixel.resize(n);
    cv::parallel_for_(
        cv::Range(0, h),
        [&](const cv::Range& rows) {
            for (int v = rows.start; v < rows.end; ++v) {
                const std::size_t row = row_of(v);
                const std::uint8_t* img_row =
                    left.data.data() + row * static_cast<std::size_t>(left.channels);
                std::size_t at = offset[static_cast<std::size_t>(v)];
                for_each_point(v, [&](int u, double y_num, double w_h, std::uint16_t cls) {
                    const double inv = 1.0 / w_h;
                    cloud.xyz_m[at] = Eigen::Vector3f(
                        static_cast<float>(x_num[static_cast<std::size_t>(u)] * inv),
                        static_cast<float>(y_num * inv), static_cast<float>(z_num * inv));
                    const std::uint8_t* c =
                        grey ? img_row + u : img_row + 3 * static_cast<std::size_t>(u);
                    cloud.colour[at] = grey ? Rgb{c[0], c[0], c[0]} : Rgb{c[0], c[1], c[2]};
                    cloud.class_index[at] = cls;
                    cloud.pixel[at] = static_cast<std::uint32_t>(row + static_cast<std::size_t>(u));
                    ++at;
                });
            }
        },
        stripes);
    return cloud;
}

}  // namespace cloud_analysis
