#pragma once

/// The project's own semi-global matcher: a centre-symmetric census transform over a 9x7 window
/// (Spangenberg et al., "Large Scale Semi-Global Matching on the CPU", IV 2014: rSGM) with the
/// Hamming distance, plus a capped absolute intensity difference (AD-Census: Mei et al., "On
/// Building an Accurate Stereo Matching System on Graphics Hardware", ICCV Workshops 2011),
/// summed over a square window as the pixel cost (the box sum steadies the noisy census of
/// uniform surfaces, as SGBM's block of costs does), and semi-global aggregation (Hirschmueller,
/// PAMI 2008) along the three paths of OpenCV's MODE_SGBM_3WAY (left to right, right to left, top
/// to bottom) in 16-bit lanes, rows in stripes over the cores. Post-processing follows
/// cv::StereoSGBM: parabolic sub-pixel step, uniqueness ratio, the left-right check against the
/// right view's winners drawn from the same cost volume (disp12MaxDiff); the output is CV_16S
/// with 4 fractional bits. Bit-exact between its AVX2 and portable kernels.

#include <cstddef>
#include <cstdint>
#include <memory>
#include <string>

namespace cloud_analysis {

/// Settings of the census SGM matcher proper (the shared ones, disparity range, uniqueness,
/// left-right check and speckles, live in DisparityOptions). Penalties and the median tuned on
/// the rendered samples (samples/rendered; docs/performance.md).
struct SgmOptions {
    int window = 5;         ///< side of the box the census costs are summed over, px, odd, 1..9
    int intensity_cap = 0;  ///< adds min(|I_left - I_right|, cap) to a pixel's census cost,
                            ///< grey levels, 0..31; 0 = census alone
    int p1 = 400;     ///< penalty of a +-1 px disparity change, census bits (cost 0..31 * window^2)
    int p2 = 2000;    ///< penalty of a larger change, census bits, > p1
    int stripes = 4;  ///< row stripes matched independently (in parallel), >= 1
    int warmup_rows = 16;               ///< rows above a stripe that prime its top-down path, >= 0
    std::string subpixel = "parabola";  ///< "parabola" (cv::StereoSGBM's) or "equiangular"
    bool median3 = true;                ///< 3x3 median of the disparity before the speckle filter
    std::string kernel = "auto";        ///< "auto" (AVX2 when the CPU has it), "avx2" or "portable"
    /// Throws std::invalid_argument naming the first bad field.
    void validate() const;
};

/// The disparity range and post-processing of one matcher call.
struct SgmRange {
    int min_disparity = 0;      ///< smallest disparity searched, px, >= 0
    int num_disparities = 128;  ///< search range, px, multiple of 16, <= 256
    int uniqueness_ratio = 0;   ///< best cost must beat the others (beyond +-1 px) by this, %
    int disp12_max_diff = 1;    ///< left-right check tolerance, px; < 0 disables
};

/// True when the CPU runs the AVX2 kernel.
bool sgm_has_avx2();

/// A census SGM matcher that keeps its working buffers across frames.
class SgmMatcher {
  public:
    explicit SgmMatcher(const SgmOptions& options);
    ~SgmMatcher();
    SgmMatcher(SgmMatcher&&) noexcept;
    SgmMatcher& operator=(SgmMatcher&&) noexcept;

    /// Disparity of the grey `left` view against `right` (both width x height, row strides in
    /// bytes), written as disparity * 16 into `out` (row stride in elements). Columns left of
    /// max(first_column, min + num - 1) and pixels that fail a check get (min - 1) * 16, as
    /// cv::StereoSGBM marks them. No speckle filtering.
    void compute(const std::uint8_t* left, const std::uint8_t* right, std::size_t stride, int width,
                 int height, int first_column, const SgmRange& range, std::int16_t* out,
                 std::size_t out_stride);

    /// Cost-volume cells (pixels x disparities) the last compute() aggregated, warm-up included.
    std::size_t last_cells() const;

  private:
    struct Impl;
    std::unique_ptr<Impl> impl_;
};

}  // namespace cloud_analysis
