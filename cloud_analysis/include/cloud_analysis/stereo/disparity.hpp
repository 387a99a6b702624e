#pragma once

/// Disparity of a rectified pair by semi-global matching (Hirschmueller, "Stereo Processing by
/// Semiglobal Matching and Mutual Information", PAMI 2008; OpenCV's cv::StereoSGBM), with an
/// optional left-right consistency check and WLS filtering (Min et al., "Fast Global Image
/// Smoothing Based on Weighted Least Squares", TIP 2014; opencv_contrib ximgproc), and the
/// KITTI 2015 scores (Menze & Geiger, CVPR 2015).

#include <array>
#include <cstddef>
#include <memory>
#include <string>

#include "cloud_analysis/io/io.hpp"
#include "cloud_analysis/stereo/sgm.hpp"

namespace cloud_analysis {

/// Largest disparity range and |min_disparity| an options struct accepts, px.
inline constexpr int kMaxDisparityRange = 4096;

/// Every cv::StereoSGBM parameter plus the post-filters. Defaults are tuned on KITTI 2015
/// frames 000000_10 and 000001_10 (docs/evaluation.md, section Disparity).
struct DisparityOptions {
    int min_disparity = 0;           ///< smallest disparity searched, px
    int num_disparities = 128;       ///< search range, px, multiple of 16
    int block_size = 9;              ///< matching window side, px, odd, 1..11 typical
    int p1 = 0;                      ///< smoothness penalty for +-1 px changes; 0 = 8*cn*block^2
    int p2 = 3200;                   ///< penalty for larger changes, > p1; 0 = 32*cn*block^2
    int disp12_max_diff = 1;         ///< SGBM internal left-right check, px; < 0 disables
    int pre_filter_cap = 31;         ///< clip of the x-derivative prefilter, 1..63
    int uniqueness_ratio = 0;        ///< best cost must beat the second by this margin, %
    int speckle_window_size = 100;   ///< max size of a speckle to remove, px; 0 disables
    int speckle_range = 2;           ///< max disparity step inside a speckle, px
    std::string mode = "sgbm_3way";  ///< "sgbm" (5 paths), "hh" (8 paths), "sgbm_3way", "hh4"
    bool pad_left = true;            ///< pad the views so the left border band gets disparities
    bool colour = false;             ///< match on RGB (cn = 3) instead of grey
    bool lr_check = false;           ///< drop pixels whose right-image match disagrees
    double lr_max_diff_px = 1.0;     ///< tolerance of that check, px
    bool wls = false;                ///< WLS edge-aware filtering (densifies the map)
    double wls_lambda = 500.0;       ///< WLS smoothness weight (ximgproc sample: 8000)
    double wls_sigma_colour = 0.8;   ///< WLS edge sensitivity (ximgproc sample: 1.5)
    int downscale = 1;  ///< match at 1/downscale resolution (1 or 2) and upsample the map, x
    /// "sgbm" (cv::StereoSGBM with the fields above) or "sgm" (the project's census SGM,
    /// stereo/sgm.hpp: grey, no WLS or full lr_check; shares the range, uniqueness,
    /// disp12_max_diff, speckle, padding and downscale fields)
    std::string matcher = "sgbm";
    SgmOptions sgm;  ///< settings of the "sgm" matcher
    /// Throws std::invalid_argument naming the first bad field.
    void validate() const;
};

/// OpenCV's samples/cpp/stereo_match.cpp settings for SGBM (SADWindowSize 3, P1 8*cn*3^2,
/// P2 32*cn*3^2, disp12MaxDiff 1, preFilterCap 63, uniquenessRatio 10, speckleWindowSize 100,
/// speckleRange 32, MODE_SGBM, colour, no padding) with numDisparities widened to 128 for KITTI.
DisparityOptions opencv_sample_disparity_options();

/// Speed presets (docs/performance.md): "tuned" (the defaults above), "fast" (half-resolution
/// matching with 64 disparities, upsampled), "quality" (the tuned matcher + WLS filtering) and
/// "opencv-sample". Throws std::invalid_argument for another name.
DisparityOptions disparity_preset(const std::string& name);

/// A matcher built once and reused across frames: it keeps OpenCV's matcher objects and their
/// working buffers, so a batch allocates them once (libSGM's StereoSGM class does the same).
class DisparityMatcher {
  public:
    /// Validates and keeps the options; throws std::invalid_argument naming the bad field.
    explicit DisparityMatcher(const DisparityOptions& options);
    ~DisparityMatcher();
    DisparityMatcher(DisparityMatcher&&) noexcept;
    DisparityMatcher& operator=(DisparityMatcher&&) noexcept;

    /// Disparity of the left image. Images must have the same size and channel count.
    DisparityMap compute(const ImageU8& left, const ImageU8& right);

    /// Milliseconds of the matcher call alone (cv::StereoSGBM::compute, or the census SGM with
    /// its speckle filter, on the same grey, scaled and padded views compute() builds): the
    /// floor the rest of the pipeline adds to.
    double time_matcher_only_ms(const ImageU8& left, const ImageU8& right);

    const DisparityOptions& options() const;

  private:
    struct Impl;
    std::unique_ptr<Impl> impl_;
};

/// Disparity of the left image with a one-off matcher. Images must have the same size and
/// channel count.
DisparityMap compute_disparity(const ImageU8& left, const ImageU8& right,
                               const DisparityOptions& options);

/// KITTI 2015 measures of an estimate against a ground-truth map (pixels with GT only).
struct DisparityScore {
    std::size_t gt_pixels = 0;   ///< pixels with a ground-truth value
    std::size_t est_pixels = 0;  ///< of those, pixels the estimate covers
    double d1_all = 0.0;         ///< outliers (err > 3 px and > 5 %) over gt_pixels; missing
                                 ///< estimates count as outliers (KITTI fills them, we do not)
    double d1_valid = 0.0;       ///< outliers over est_pixels only
    double epe_px = 0.0;         ///< mean |error| over est_pixels, px
    double density = 0.0;        ///< est_pixels / gt_pixels
    /// Median signed error (estimate - truth) of the estimates within 3 px whose true
    /// disparity is under kBiasBandsPx[0], under kBiasBandsPx[1], and at least that, px (0 for
    /// a band without pixels): the matcher's bias by range. Depth is fb / d, so a bias of -0.5
    /// px at 20 px puts things 2.5 % farther.
    std::array<double, 3> bias_px{};
    static constexpr std::array<double, 2> kBiasBandsPx = {25.0, 50.0};
};

/// Scores `estimate` against `ground_truth` (same size; values <= 0 mean missing).
DisparityScore score_disparity(const DisparityMap& estimate, const DisparityMap& ground_truth);

}  // namespace cloud_analysis
