#include "cloud_analysis/stereo/disparity.hpp"

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <stdexcept>
#include <vector>

#include <opencv2/calib3d.hpp>
#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>
#include <opencv2/ximgproc/disparity_filter.hpp>

#include "cloud_analysis/io/mat_view.hpp"
#include "cloud_analysis/support/select.hpp"

namespace cloud_analysis {
namespace {

[[noreturn]] void bad(const std::string& field, const std::string& rule) {
    throw std::invalid_argument(field + ": " + rule);
}

int sgbm_mode(const std::string& mode) {
    if (mode == "sgbm") return cv::StereoSGBM::MODE_SGBM;
    if (mode == "hh") return cv::StereoSGBM::MODE_HH;
    if (mode == "sgbm_3way") return cv::StereoSGBM::MODE_SGBM_3WAY;
    if (mode == "hh4") return cv::StereoSGBM::MODE_HH4;
    bad("mode", "must be sgbm, hh, sgbm_3way or hh4");
}

}  // namespace

void DisparityOptions::validate() const {
    if (num_disparities <= 0 || num_disparities % 16 != 0) {
        bad("num_disparities", "must be a positive multiple of 16");
    }
    // Bounds that keep every later sum ((min_disparity - 1) * 16, padding) far from int overflow;
    // no camera needs more than a few hundred pixels of disparity.
    if (num_disparities > kMaxDisparityRange) {
        bad("num_disparities", "must be <= " + std::to_string(kMaxDisparityRange));
    }
    if (min_disparity < -kMaxDisparityRange || min_disparity > kMaxDisparityRange) {
        bad("min_disparity", "must be within +-" + std::to_string(kMaxDisparityRange));
    }
    if (block_size < 1 || block_size % 2 == 0 || block_size > 31) {
        bad("block_size", "must be odd, 1..31");
    }
    if (p1 < 0) bad("p1", "must be >= 0");
    if (p2 < 0) bad("p2", "must be >= 0");
    if (p1 > 0 && p2 > 0 && p2 <= p1) bad("p2", "must be > p1");
    if (pre_filter_cap < 1 || pre_filter_cap > 63) bad("pre_filter_cap", "must be 1..63");
    if (uniqueness_ratio < 0 || uniqueness_ratio > 100) bad("uniqueness_ratio", "must be 0..100");
    if (speckle_window_size < 0) bad("speckle_window_size", "must be >= 0");
    if (speckle_range < 0) bad("speckle_range", "must be >= 0");
    sgbm_mode(mode);
    if (!(lr_max_diff_px >= 0.0)) bad("lr_max_diff_px", "must be >= 0");
    if (!(wls_lambda > 0.0)) bad("wls_lambda", "must be > 0");
    if (!(wls_sigma_colour > 0.0)) bad("wls_sigma_colour", "must be > 0");
    if (downscale != 1 && downscale != 2) bad("downscale", "must be 1 or 2");
    if (matcher != "sgbm" && matcher != "sgm") bad("matcher", "must be sgbm or sgm");
    if (matcher == "sgm") {
        sgm.validate();
        if (min_disparity < 0) bad("min_disparity", "must be >= 0 with the sgm matcher");
        if (num_disparities / downscale > 256) bad("num_disparities", "must be <= 256 with sgm");
        if (uniqueness_ratio > 99) bad("uniqueness_ratio", "must be 0..99 with the sgm matcher");
        if (colour) bad("colour", "the sgm matcher matches grey views");
        if (lr_check) bad("lr_check", "the sgm matcher checks with disp12_max_diff");
        if (wls) bad("wls", "the sgm matcher has no WLS filter");
    }
}

DisparityOptions opencv_sample_disparity_options() {
    DisparityOptions o;
    o.min_disparity = 0;
    o.num_disparities = 128;
    o.block_size = 3;
    o.p1 = 8 * 3 * 3 * 3;
    o.p2 = 32 * 3 * 3 * 3;
    o.disp12_max_diff = 1;
    o.pre_filter_cap = 63;
    o.uniqueness_ratio = 10;
    o.speckle_window_size = 100;
    o.speckle_range = 32;
    o.mode = "sgbm";
    o.colour = true;
    o.pad_left = false;
    return o;
}

DisparityOptions disparity_preset(const std::string& name) {
    if (name == "tuned") return DisparityOptions{};
    if (name == "opencv-sample") return opencv_sample_disparity_options();
    if (name == "fast") {
        // Half the pixels in each direction: 64 disparities at half scale cover the same 128 px
        // of range; the smaller window keeps the same footprint in the scene.
        DisparityOptions o;
        o.downscale = 2;
        o.block_size = 5;
        o.p2 = 0;
        o.speckle_window_size = 25;
        // The census matcher's penalties at half scale, tuned on the rendered samples.
        o.sgm.p1 = 200;
        o.sgm.p2 = 1000;
        return o;
    }
    if (name == "quality") {
        // WLS fills and smooths the tuned map: kitti15 D1-all 9.3/8.3 % -> 6.9/6.2 %. The
        // 5-path and 8-path modes were worse with these penalties (docs/performance.md).
        DisparityOptions o;
        o.wls = true;
        return o;
    }
    bad("preset", "must be tuned, fast, quality or opencv-sample");
}

struct DisparityMatcher::Impl {
    DisparityOptions options;
    cv::Ptr<cv::StereoSGBM> sgbm;
    cv::Ptr<cv::StereoMatcher> right_matcher;                 // lr-check / WLS only
    cv::Ptr<cv::ximgproc::DisparityWLSFilter> wls;            // WLS only
    cv::Mat lp, rp, raw_left, raw_right, filtered, up, grey;  // reused buffers
    std::unique_ptr<SgmMatcher> own;                          // "sgm" matcher only
    cv::Mat speckle_buffer, median_in, median_out;            // its post-filters'

    /// The left disparity of lp and rp into raw_left (CV_16S, disparity * 16).
    void match_left() {
        if (!own) {
            sgbm->compute(lp, rp, raw_left);
            return;
        }
        raw_left.create(lp.size(), CV_16S);
        SgmRange range;
        range.min_disparity = options.min_disparity;
        range.num_disparities = matched_disparities();
        range.uniqueness_ratio = options.uniqueness_ratio;
        range.disp12_max_diff = options.disp12_max_diff;
        own->compute(lp.data, rp.data, lp.step, lp.cols, lp.rows, pad(), range,
                     raw_left.ptr<std::int16_t>(), raw_left.step1());
        if (options.sgm.median3) {
            // As 16-bit unsigned (the invalid value becomes 0), which medianBlur takes.
            const int invalid = (options.min_disparity - 1) * 16;
            raw_left.convertTo(median_in, CV_16U, 1.0, -invalid);
            cv::medianBlur(median_in, median_out, 3);
            median_out.convertTo(raw_left, CV_16S, 1.0, invalid);
        }
        if (options.speckle_window_size > 0) {
            cv::filterSpeckles(raw_left, (options.min_disparity - 1) * 16,
                               options.speckle_window_size, 16 * options.speckle_range,
                               speckle_buffer);
        }
    }

    int pad() const {
        return options.pad_left ? std::max(0, options.min_disparity + matched_disparities()) : 0;
    }
    int matched_disparities() const {
        // At 1/s scale the same metric range needs 1/s of the disparities (multiple of 16).
        const int n = options.num_disparities / options.downscale;
        return std::max(16, (n + 15) / 16 * 16);
    }

    /// Grey (unless colour), scaled and left-padded views into lp and rp. The views are
    /// written straight into the padded buffers, which are allocated and zeroed only when the
    /// frame size changes: no per-frame copy for the padding.
    void prepare(const ImageU8& left, const ImageU8& right) {
        if (left.width_px != right.width_px || left.height_px != right.height_px) {
            throw std::invalid_argument("left and right images differ in size");
        }
        if (left.channels != right.channels) {
            throw std::invalid_argument("left and right images differ in channel count");
        }
        if (left.empty()) throw std::invalid_argument("empty images");
        const bool to_grey = left.channels == 3 && !options.colour;
        const int type = CV_8UC(to_grey ? 1 : left.channels);
        const int width = left.width_px / options.downscale;
        const int height = left.height_px / options.downscale;
        // StereoSGBM leaves the first min + num disparities columns empty. Padding both views
        // on the left with black lets those pixels match wherever their partner is in view.
        const int p = pad();
        if (lp.rows != height || lp.cols != width + p || lp.type() != type) {
            lp.create(height, width + p, type);
            rp.create(height, width + p, type);
            lp.setTo(cv::Scalar::all(0));
            rp.setTo(cv::Scalar::all(0));
        }
        const cv::Rect view(p, 0, width, height);
        fill(left, to_grey, lp(view));
        fill(right, to_grey, rp(view));
    }

    /// Converts (grey) and scales `img` into `dst`, a view of the padded buffer.
    void fill(const ImageU8& img, bool to_grey, cv::Mat dst) {
        const cv::Mat src = mat_view(img);
        if (options.downscale == 1) {
            if (to_grey) {
                cv::cvtColor(src, dst, cv::COLOR_RGB2GRAY);
            } else {
                src.copyTo(dst);
            }
            return;
        }
        const cv::Mat* scaled_from = &src;
        if (to_grey) {
            cv::cvtColor(src, grey, cv::COLOR_RGB2GRAY);
            scaled_from = &grey;
        }
        cv::resize(*scaled_from, dst, dst.size(), 0, 0, cv::INTER_AREA);
    }
};

DisparityMatcher::DisparityMatcher(const DisparityOptions& options)
    : impl_(std::make_unique<Impl>()) {
    options.validate();
    impl_->options = options;
    const int cn = options.colour ? 3 : 1;
    const int area = options.block_size * options.block_size;
    const int p1 = options.p1 > 0 ? options.p1 : 8 * cn * area;
    const int p2 = options.p2 > 0 ? options.p2 : 32 * cn * area;
    impl_->sgbm = cv::StereoSGBM::create(options.min_disparity, impl_->matched_disparities(),
                                         options.block_size, p1, std::max(p2, p1 + 1),
                                         options.disp12_max_diff, options.pre_filter_cap,
                                         options.uniqueness_ratio, options.speckle_window_size,
                                         options.speckle_range, sgbm_mode(options.mode));
    if (options.matcher == "sgm") impl_->own = std::make_unique<SgmMatcher>(options.sgm);
    if (options.lr_check || options.wls) {
        impl_->right_matcher = cv::ximgproc::createRightMatcher(impl_->sgbm);
    }
    if (options.wls) {
        impl_->wls = cv::ximgproc::createDisparityWLSFilter(impl_->sgbm);
        impl_->wls->setLambda(options.wls_lambda);
        impl_->wls->setSigmaColor(options.wls_sigma_colour);
    }
}

DisparityMatcher::~DisparityMatcher() = default;
DisparityMatcher::DisparityMatcher(DisparityMatcher&&) noexcept = default;
DisparityMatcher& DisparityMatcher::operator=(DisparityMatcher&&) noexcept = default;

const DisparityOptions& DisparityMatcher::options() const { return impl_->options; }

double DisparityMatcher::time_matcher_only_ms(const ImageU8& left, const ImageU8& right) {
    Impl& m = *impl_;
    m.prepare(left, right);
    const auto start = std::chrono::steady_clock::now();
    m.match_left();
    return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start)
        .count();
}

DisparityMap DisparityMatcher::compute(const ImageU8& left, const ImageU8& right) {
    Impl& m = *impl_;
    const DisparityOptions& options = m.options;
    m.prepare(left, right);
    m.match_left();  // CV_16S, disparity * 16
    const bool need_right = options.lr_check || options.wls;
    if (need_right) m.right_matcher->compute(m.rp, m.lp, m.raw_right);  // negative disparities
    cv::Mat raw_left = m.raw_left;
    if (options.wls) {
        m.wls->filter(m.raw_left, m.lp, m.filtered, m.raw_right);
        raw_left = m.filtered;
    }
    const int pad = m.pad();
    const int scaled_width = m.lp.cols - pad;
    raw_left = raw_left.colRange(pad, pad + scaled_width);
    cv::Mat raw_right;
    if (need_right) raw_right = m.raw_right.colRange(pad, pad + scaled_width);
    const int scale = options.downscale;
    if (scale > 1) {
        // Nearest neighbour: a missing value must not blend into its valid neighbours.
        const cv::Size full(left.width_px, left.height_px);
        cv::resize(raw_left, m.up, full, 0, 0, cv::INTER_NEAREST);
        raw_left = m.up;
        if (options.lr_check) {
            cv::Mat up_right;
            cv::resize(raw_right, up_right, full, 0, 0, cv::INTER_NEAREST);
            raw_right = up_right;
        }
    }
    const int invalid_raw = (options.min_disparity - 1) * 16;
    const float to_px = static_cast<float>(scale) / 16.0f;

    // Every element is written once: kNoDisparity or the value in px.
    DisparityMap out;
    out.width_px = left.width_px;
    out.height_px = left.height_px;
    out.disparity_px.resize(static_cast<std::size_t>(out.width_px) * out.height_px);
    const std::int16_t lowest_valid = static_cast<std::int16_t>(std::max(invalid_raw, 0) + 1);
    const float lr_max_diff = static_cast<float>(options.lr_max_diff_px);
    // Rows in parallel stripes (each row on its own: the same values as one pass).
    const auto convert_rows = [&](const cv::Range& rows) {
        for (int v = rows.start; v < rows.end; ++v) {
            const auto* row = raw_left.ptr<std::int16_t>(v);
            const std::int16_t* row_r = options.lr_check ? raw_right.ptr<std::int16_t>(v) : nullptr;
            float* dst = out.disparity_px.data() + static_cast<std::size_t>(v) * out.width_px;
            if (row_r == nullptr) {
                for (int u = 0; u < raw_left.cols; ++u) {
                    dst[u] =
                        row[u] >= lowest_valid ? static_cast<float>(row[u]) * to_px : kNoDisparity;
                }
                continue;
            }
            for (int u = 0; u < raw_left.cols; ++u) {
                dst[u] = kNoDisparity;
                if (row[u] < lowest_valid) continue;
                const float d = static_cast<float>(row[u]) * to_px;
                const int ur = static_cast<int>(std::lround(static_cast<float>(u) - d));
                if (ur < 0) continue;
                const float dr = -static_cast<float>(row_r[ur]) * to_px;
                if (!(dr > 0.0f) || std::abs(dr - d) > lr_max_diff) continue;
                dst[u] = d;
            }
        }
    };
    cv::parallel_for_(cv::Range(0, raw_left.rows), convert_rows, std::min(raw_left.rows, 8));
    return out;
}

DisparityMap compute_disparity(const ImageU8& left, const ImageU8& right,
                               const DisparityOptions& options) {
    return DisparityMatcher(options).compute(left, right);
}

DisparityScore score_disparity(const DisparityMap& estimate, const DisparityMap& ground_truth) {
    if (estimate.width_px != ground_truth.width_px ||
        estimate.height_px != ground_truth.height_px) {
        throw std::invalid_argument("estimate and ground truth differ in size");
    }
    DisparityScore s;
    std::size_t outliers_valid = 0;
    double abs_sum = 0.0;
    std::array<std::vector<double>, 3> signed_errors;
    for (std::size_t i = 0; i < ground_truth.disparity_px.size(); ++i) {
        const float gt = ground_truth.disparity_px[i];
        if (!(gt > 0.0f)) continue;
        ++s.gt_pixels;
        const float est = estimate.disparity_px[i];
        if (!(est > 0.0f)) continue;
        ++s.est_pixels;
        const double signed_err = static_cast<double>(est) - static_cast<double>(gt);
        const double err = std::abs(signed_err);
        abs_sum += err;
        if (err > 3.0 && err > 0.05 * static_cast<double>(gt)) ++outliers_valid;
        if (err <= 3.0) {
            const auto& bands = DisparityScore::kBiasBandsPx;
            const auto g = static_cast<double>(gt);
            const std::size_t band = g < bands[0] ? 0 : g < bands[1] ? 1 : 2;
            signed_errors[band].push_back(signed_err);
        }
    }
    for (std::size_t b = 0; b < signed_errors.size(); ++b) {
        s.bias_px[b] = median(std::move(signed_errors[b]));
    }
    const std::size_t outliers_all = outliers_valid + (s.gt_pixels - s.est_pixels);
    if (s.gt_pixels > 0) {
        s.d1_all = static_cast<double>(outliers_all) / static_cast<double>(s.gt_pixels);
        s.density = static_cast<double>(s.est_pixels) / static_cast<double>(s.gt_pixels);
    }
    if (s.est_pixels > 0) {
        s.d1_valid = static_cast<double>(outliers_valid) / static_cast<double>(s.est_pixels);
        s.epe_px = abs_sum / static_cast<double>(s.est_pixels);
    }
    return s;
}

}  // namespace cloud_analysis
