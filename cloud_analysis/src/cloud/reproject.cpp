#include "cloud_analysis/cloud/reproject.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <utility>
#include <vector>

#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>

namespace cloud_analysis {
namespace {

/// The reprojection of one pixel row at a time, shared by reproject and reproject_by_class so
/// that both keep exactly the same points with exactly the same coordinates.
class RowReprojector {
  public:
    RowReprojector(const DisparityMap& disparity, const StereoCamera& camera,
                   const ClassImage& classes, const ReprojectOptions& options)
        : disparity_(disparity), classes_(classes), options_(options) {
        options.validate();
        const int w = disparity.width_px;
        labelled_ = !classes.class_index.empty();
        if (labelled_ && (classes.width_px != w || classes.height_px != disparity.height_px)) {
            throw std::invalid_argument("semantic image and disparity differ in size");
        }
        if (!(camera.baseline_m > 0.0) || !(camera.fx_px > 0.0) || !(camera.fy_px > 0.0)) {
            throw std::invalid_argument("camera: fx, fy and baseline must be > 0");
        }
        // (X, Y, Z, W) = Q (u, v, d, 1) with OpenCV's Q (reprojection_matrix): X = u - cx,
        // Y = (v - cy) fx / fy, Z = fx, W = (d - (cx - cx_right)) / B. Only W depends on d, so
        // the 4x4 product reduces to one reciprocal per point; rows and columns are precomputed.
        Q_ = reprojection_matrix(camera);
        z_num_ = Q_(2, 3);
        x_num_.resize(static_cast<std::size_t>(w));
        x_num_sq_.resize(x_num_.size());
        for (int u = 0; u < w; ++u) {
            const auto i = static_cast<std::size_t>(u);
            x_num_[i] = Q_(0, 0) * u + Q_(0, 3);
            x_num_sq_[i] = x_num_[i] * x_num_[i];
        }
        max_range_sq_ = options.max_range_m * options.max_range_m;
    }

    int width() const { return disparity_.width_px; }
    int height() const { return disparity_.height_px; }

    std::size_t row_start(int v) const {
        return static_cast<std::size_t>(v) * static_cast<std::size_t>(width());
    }

    /// Calls emit(u, y_num, w_h, class) for each pixel of row v that becomes a point and whose
    /// column and class `wanted` accepts (tested first), in order. The range test needs no
    /// division: |(X, Y, Z)| / W <= r  <=>  |(X, Y, Z)|^2 <= r^2 W^2, W > 0.
    template <typename Wanted, typename Emit>
    void for_each_point(int v, Wanted&& wanted, Emit&& emit) const {
        const Row r = row(v);
        const bool keep_void = options_.keep_void;
        for (int u = 0; u < width(); ++u) {
            const std::uint16_t cls = labelled_ ? r.cls[u] : kVoidClass;
            if (!wanted(u, cls)) continue;
            const double d = r.d[u];
            if (!(d > r.min_d)) continue;
            if (cls == kVoidClass && !keep_void) continue;
            const double w_h = r.w_per_px * d + r.w_offset;
            if (!(w_h > 0.0)) continue;  // at or beyond infinity
            if (!(x_num_sq_[static_cast<std::size_t>(u)] + r.yz_num_sq <=
                  max_range_sq_ * w_h * w_h)) {
                continue;
            }
            emit(u, r.y_num, w_h, cls);
        }
    }

    /// The same for every pixel.
    template <typename Emit>
    void for_each_point(int v, Emit&& emit) const {
        for_each_point(
            v, [](int, std::uint16_t) { return true; }, emit);
    }

    /// Points of row v: the pixels for_each_point emits, counted without branches.
    std::size_t count_points(int v) const {
        if (!options_.keep_void && !labelled_) return 0;
        const Row r = row(v);
        const bool all_classes = options_.keep_void || !labelled_;
        std::size_t n = 0;
        for (int u = 0; u < width(); ++u) {
            const double d = r.d[u];
            const double w_h = r.w_per_px * d + r.w_offset;
            const bool point = (d > r.min_d) & (w_h > 0.0) &
                               (x_num_sq_[static_cast<std::size_t>(u)] + r.yz_num_sq <=
                                max_range_sq_ * w_h * w_h) &
                               (all_classes || r.cls[u] != kVoidClass);
            n += point ? 1 : 0;
        }
        return n;
    }

    /// The point of column u of a row emitted with (y_num, w_h).
    Eigen::Vector3f point(int u, double y_num, double w_h) const {
        const double inv = 1.0 / w_h;
        return {static_cast<float>(x_num_[static_cast<std::size_t>(u)] * inv),
                static_cast<float>(y_num * inv), static_cast<float>(z_num_ * inv)};
    }

    /// Calls body(first_row, last_row) for row stripes in parallel.
    template <typename Body>
    void for_stripes(Body&& body) const {
        const int h = height();
        cv::parallel_for_(
            cv::Range(0, h), [&](const cv::Range& rows) { body(rows.start, rows.end); },
            std::max(1, std::min(h, 16)));
    }

  private:
    /// Row v's inputs and the terms that are constant along it.
    struct Row {
        const float* d;            ///< disparities, px
        const std::uint16_t* cls;  ///< classes; null without a class image
        double y_num;              ///< Y of the row before the division by W
        double yz_num_sq;          ///< Y^2 + Z^2 before the division by W^2
        double w_per_px;           ///< W = w_per_px * d + w_offset
        double w_offset;
        double min_d;  ///< disparities at or below this give no point
    };
    Row row(int v) const {
        const std::size_t start = row_start(v);
        const double y_num = Q_(1, 1) * v + Q_(1, 3);
        return {disparity_.disparity_px.data() + start,
                labelled_ ? classes_.class_index.data() + start : nullptr,
                y_num,
                y_num * y_num + z_num_ * z_num_,
                Q_(3, 2),
                Q_(3, 3),
                options_.min_disparity_px};
    }

    const DisparityMap& disparity_;
    const ClassImage& classes_;
    const ReprojectOptions& options_;
    bool labelled_ = false;
    Eigen::Matrix4d Q_;
    double z_num_ = 0.0;
    std::vector<double> x_num_, x_num_sq_;
    double max_range_sq_ = 0.0;
};

/// A point reproject_by_class keeps: its position, pixel and class.
struct Taken {
    Eigen::Vector3f xyz;
    std::uint32_t pixel;
    std::uint16_t cls;
};

/// The points reproject_by_class keeps, per row stripe, and how many.
struct StripePoints {
    int stripes = 1;                        ///< row stripes
    std::size_t slots = 1;                  ///< per stripe: one per class, then one for all
    std::vector<std::vector<Taken>> taken;  ///< per stripe: the points kept, in pixel order
    std::vector<std::size_t> count;         ///< per stripe and slot: points
};

/// The first pass of reproject_by_class: over the pixels in parallel row stripes, each
/// stripe's points that `selection` keeps (and its points of every class).
StripePoints take_points(const RowReprojector& rows, const ClassSelection& selection) {
    const int h = rows.height();
    const std::size_t k_count = selection.column_mask.size();
    const double max_depth = selection.max_depth_m;
    const std::uint32_t lattice = selection.lattice_mask;
    const auto in_depth = [&](const Eigen::Vector3f& p) {
        return p.z() > 0.0f && double{p.z()} < max_depth && p.allFinite();
    };
    const int stripes = std::max(1, std::min(h, 16));
    const auto first_row = [&](int s) { return static_cast<int>(std::int64_t{h} * s / stripes); };
    // Per stripe and class (the last slot: every point of the stripe).
    const std::size_t slots = k_count + 1;
    StripePoints kept{stripes, slots,
                      std::vector<std::vector<Taken>>(static_cast<std::size_t>(stripes)),
                      std::vector<std::size_t>(static_cast<std::size_t>(stripes) * slots, 0)};
    auto& taken = kept.taken;
    auto& count = kept.count;
    cv::parallel_for_(cv::Range(0, stripes), [&](const cv::Range& range) {
        for (int s = range.start; s < range.end; ++s) {
            auto& mine = taken[static_cast<std::size_t>(s)];
            mine.reserve(static_cast<std::size_t>(first_row(s + 1) - first_row(s)) *
                         static_cast<std::size_t>(rows.width()));
            std::size_t* n = count.data() + static_cast<std::size_t>(s) * slots;
            for (int v = first_row(s); v < first_row(s + 1); ++v) {
                const std::size_t row = rows.row_start(v);
                n[k_count] += rows.count_points(v);
                // The extractor's own tests on a point of class cls at column u of this row (as
                // points_by_class makes them on the cloud).
                const auto row_v = static_cast<std::uint32_t>(v);
                const auto selected = [&](int u, std::uint16_t cls) {
                    return cls < k_count &&
                           pixel_taken(selection.column_mask[cls], selection.keep_pixels[cls] != 0,
                                       lattice, static_cast<std::uint32_t>(u), row_v);
                };
                rows.for_each_point(
                    v, selected, [&](int u, double y_num, double w_h, std::uint16_t cls) {
                        const Eigen::Vector3f p = rows.point(u, y_num, w_h);
                        if (!in_depth(p)) return;
                        ++n[cls];
                        mine.push_back(
                            {p, static_cast<std::uint32_t>(row + static_cast<std::size_t>(u)),
                             cls});
                    });
            }
        }
    });
    return kept;
}

/// Counts become offsets: per class, stripes in order. Returns the slots' totals.
std::vector<std::size_t> counts_to_offsets(StripePoints& kept) {
    const std::size_t slots = kept.slots;
    std::vector<std::size_t>& count = kept.count;
    std::vector<std::size_t> total(slots, 0);
    for (std::size_t s = 0; s < static_cast<std::size_t>(kept.stripes); ++s) {
        for (std::size_t k = 0; k < slots; ++k) {
            total[k] += std::exchange(count[s * slots + k], total[k]);
        }
    }
    return total;
}

/// The second pass of reproject_by_class: copies the points kept to their classes (sized),
/// each stripe's from its offsets (counts_to_offsets) on, stripes in parallel.
void copy_to_classes(StripePoints& kept, const std::vector<char>& keep_pixels, ClassPoints& out) {
    const std::size_t slots = kept.slots;
    cv::parallel_for_(cv::Range(0, kept.stripes), [&](const cv::Range& range) {
        for (int s = range.start; s < range.end; ++s) {
            std::size_t* at = kept.count.data() + static_cast<std::size_t>(s) * slots;
            for (const Taken& t : kept.taken[static_cast<std::size_t>(s)]) {
                if (keep_pixels[t.cls]) out.pixel[t.cls][at[t.cls]] = t.pixel;
                out.xyz_m[t.cls][at[t.cls]++] = t.xyz;
            }
        }
    });
}

}  // namespace

Eigen::Matrix4d reprojection_matrix(const StereoCamera& c) {
    // OpenCV stereoRectify's Q with Tx = -baseline (right camera at +x).
    Eigen::Matrix4d Q = Eigen::Matrix4d::Zero();
    Q(0, 0) = 1.0;
    Q(0, 3) = -c.cx_px;
    Q(1, 1) = c.fx_px / c.fy_px;  // square pixels make this 1
    Q(1, 3) = -c.cy_px * c.fx_px / c.fy_px;
    Q(2, 3) = c.fx_px;
    Q(3, 2) = 1.0 / c.baseline_m;
    Q(3, 3) = -(c.cx_px - c.cx_right_px) / c.baseline_m;
    return Q;
}

void ReprojectOptions::validate() const {
    if (!(max_range_m > 0.0)) throw std::invalid_argument("max_range_m: must be > 0");
    if (!(min_disparity_px >= 0.0)) throw std::invalid_argument("min_disparity_px: must be >= 0");
    if (!(depth_edge_step_m >= 0.0) || !std::isfinite(depth_edge_step_m)) {
        throw std::invalid_argument("depth_edge_step_m: must be >= 0");
    }
    if (depth_edge_rows < 0 || depth_edge_rows > 64) {
        throw std::invalid_argument("depth_edge_rows: must be in [0, 64]");
    }
}

std::vector<std::uint8_t> depth_edge_band(const DisparityMap& disparity, const MatchBorder& border,
                                          double step_m, int rows) {
    const int w = disparity.width_px, h = disparity.height_px;
    const auto n = static_cast<std::size_t>(w) * static_cast<std::size_t>(h);
    if (!(step_m > 0.0) || rows <= 0 || !(border.fb_px_m > 0.0) || w <= 0 || h <= 0 ||
        disparity.disparity_px.size() != n) {
        return {};
    }
    // The largest disparity (the nearest surface) within `rows` rows of each pixel.
    const cv::Mat d(h, w, CV_32F, const_cast<float*>(disparity.disparity_px.data()));
    cv::Mat nearest;
    cv::dilate(d, nearest, cv::getStructuringElement(cv::MORPH_RECT, cv::Size(1, 2 * rows + 1)));
    std::vector<std::uint8_t> band(n, 0);
    const auto fb = static_cast<float>(border.fb_px_m), off = static_cast<float>(border.offset_px);
    const auto step = static_cast<float>(step_m);
    cv::parallel_for_(cv::Range(0, h), [&](const cv::Range& range) {
        for (int v = range.start; v < range.end; ++v) {
            const float* dv = d.ptr<float>(v);
            const float* nv = nearest.ptr<float>(v);
            std::uint8_t* out =
                band.data() + static_cast<std::size_t>(v) * static_cast<std::size_t>(w);
            // fb / own - fb / near >= step  <=>  fb (near - own) >= step own near, own > 0.
            for (int u = 0; u < w; ++u) {
                const float own = dv[u] - off, near = nv[u] - off;
                out[u] = own > 0.0f && fb * (near - own) >= step * own * near ? 1 : 0;
            }
        }
    });
    return band;
}

LabeledCloud reproject(const DisparityMap& disparity, const StereoCamera& camera,
                       const ImageU8& left, const ClassImage& classes,
                       const ReprojectOptions& options) {
    if (left.width_px != disparity.width_px || left.height_px != disparity.height_px) {
        throw std::invalid_argument("left image and disparity differ in size");
    }
    const RowReprojector rows(disparity, camera, classes, options);
    const int h = rows.height();
    const bool grey = left.channels != 3;
    // Rows in parallel stripes, twice: the points of each row are counted, then written from
    // the row's offset (the same tests in the same order, so the counts hold): the cloud comes
    // out in pixel order, as from one pass.
    std::vector<std::size_t> offset(static_cast<std::size_t>(h) + 1, 0);
    rows.for_stripes([&](int first, int last) {
        for (int v = first; v < last; ++v) {
            offset[static_cast<std::size_t>(v) + 1] = rows.count_points(v);
        }
    });
    for (std::size_t v = 0; v < static_cast<std::size_t>(h); ++v) offset[v + 1] += offset[v];
    LabeledCloud cloud;
    cloud.width_px = rows.width();
    cloud.height_px = h;
    cloud.border = match_border(camera);
    cloud.depth_edge = depth_edge_band(disparity, cloud.border, options.depth_edge_step_m,
                                       options.depth_edge_rows);
    const std::size_t n = offset.back();
    cloud.xyz_m.resize(n);
    cloud.colour.resize(n);
    cloud.class_index.resize(n);
    cloud.pixel.resize(n);
    rows.for_stripes([&](int first, int last) {
        for (int v = first; v < last; ++v) {
            const std::size_t row = rows.row_start(v);
            const std::uint8_t* img_row =
                left.data.data() + row * static_cast<std::size_t>(left.channels);
            std::size_t at = offset[static_cast<std::size_t>(v)];
            rows.for_each_point(v, [&](int u, double y_num, double w_h, std::uint16_t cls) {
                cloud.xyz_m[at] = rows.point(u, y_num, w_h);
                const std::uint8_t* c =
                    grey ? img_row + u : img_row + 3 * static_cast<std::size_t>(u);
                cloud.colour[at] = grey ? Rgb{c[0], c[0], c[0]} : Rgb{c[0], c[1], c[2]};
                cloud.class_index[at] = cls;
                cloud.pixel[at] = static_cast<std::uint32_t>(row + static_cast<std::size_t>(u));
                ++at;
            });
        }
    });
    return cloud;
}

ClassPoints reproject_by_class(const DisparityMap& disparity, const StereoCamera& camera,
                               const ClassImage& classes, const ReprojectOptions& options,
                               const ClassSelection& selection) {
    if (selection.keep_pixels.size() != selection.column_mask.size()) {
        throw std::invalid_argument("selection: column_mask and keep_pixels differ in size");
    }
    const RowReprojector rows(disparity, camera, classes, options);
    const int h = rows.height();
    const std::size_t k_count = selection.column_mask.size();
    // One pass over the pixels in parallel row stripes keeps each stripe's selected points (and
    // counts its points of every class); a second one copies them to their classes, stripes in
    // order: every class comes out in pixel order.
    StripePoints kept = take_points(rows, selection);
    ClassPoints out;
    out.width_px = rows.width();
    out.height_px = h;
    out.border = match_border(camera);
    out.depth_edge =
        depth_edge_band(disparity, out.border, options.depth_edge_step_m, options.depth_edge_rows);
    out.xyz_m.resize(k_count);
    out.pixel.resize(k_count);
    out.weight.resize(k_count);
    for (std::size_t k = 0; k < k_count; ++k) {
        out.weight[k] = std::size_t{selection.column_mask[k]} + 1;
    }
    const std::vector<std::size_t> total = counts_to_offsets(kept);
    out.cloud_points = total[k_count];
    for (std::size_t k = 0; k < k_count; ++k) {
        out.xyz_m[k].resize(total[k]);
        if (selection.keep_pixels[k]) out.pixel[k].resize(total[k]);
    }
    copy_to_classes(kept, selection.keep_pixels, out);
    return out;
}

}  // namespace cloud_analysis
