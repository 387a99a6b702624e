#pragma once

/// Whether an obstacle segment of the stereo-only path is a vehicle, or a person, learnt instead
/// of ruled: OpenCV's random trees (Breiman, "Random Forests", Machine Learning 45, 2001) over
/// what stereo and the left image measure of the segment (segment_features()), one model for
/// each question. Trained on rendered streets only, never on a real image
/// (scripts/train-segment-classifier.py [--target person]; docs/stereo-only.md).

#include <array>
#include <filesystem>
#include <memory>
#include <string>
#include <vector>

namespace cloud_analysis::geometry {

struct Segment;

/// The measurements the classifier reads, in this order (Segment's members; see there).
inline constexpr std::array<const char*, 25> kSegmentFeatureNames = {
    "top_m",           "top_q25_m",     "low_m",   "width_m",
    "thickness_m",     "depth_m",       "near_m",  "far_m",
    "green",           "occluded",      "tall",    "horizontal_edges",
    "top_spread_m",    "depth_range_m", "area_m2", "chroma_r",
    "chroma_g",        "chroma_b",      "fill",    "luma",
    "luma_cv",         "grad",          "rough_h", "rough_v",
    "disparity_spread"};

/// A segment's measurements as the classifier reads them (kSegmentFeatureNames). The area seen
/// is pixels z^2 / (fx fy): the same for any rig that sees the same surface.
std::vector<float> segment_features(const Segment& segment, double fx_px, double fy_px);

/// What a classifier's trees answer of a segment: a vehicle or not, a person or not.
enum class SegmentTarget { vehicle, person };

/// "vehicle" or "person".
std::string target_name(SegmentTarget target);

/// A trained target-or-not classifier.
class SegmentClassifier {
  public:
    /// Reads a classifier's manifest (JSON: "format" "stereoscene-<target>-classifier" with
    /// <target> target_name(target), "version" 1, "model" the trees' file beside it as
    /// cv::ml::RTrees::save wrote it, two classes, 0 not the target and 1 the target;
    /// "features" kSegmentFeatureNames in order; "vote_threshold" in (0, 1)) and its trees.
    /// Throws std::runtime_error "<file>: <reason>".
    static std::shared_ptr<const SegmentClassifier> load(
        const std::filesystem::path& manifest, SegmentTarget target = SegmentTarget::vehicle);

    /// Share of the trees that call these features the target, [0, 1].
    double votes(const std::vector<float>& features) const;
    /// A segment is the target when more than this share of the trees call it one.
    double vote_threshold() const;

    ~SegmentClassifier();
    SegmentClassifier(const SegmentClassifier&) = delete;
    SegmentClassifier& operator=(const SegmentClassifier&) = delete;

  private:
    struct Impl;
    explicit SegmentClassifier(std::unique_ptr<Impl> impl);
    std::unique_ptr<Impl> impl_;
};

/// The project's model: classifiers/<target>-segments.json in the asset folder.
std::filesystem::path default_segment_classifier_path(
    SegmentTarget target = SegmentTarget::vehicle);

}  // namespace cloud_analysis::geometry
