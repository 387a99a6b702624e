#include "cloud_analysis/geometry/segment_classifier.hpp"

#include <functional>
#include <stdexcept>
#include <string>
#include <system_error>

#include <opencv2/core.hpp>
#include <opencv2/ml.hpp>

#include <nlohmann/json.hpp>

#include "cloud_analysis/geometry/scene_geometry.hpp"
#include "scene_schema/entities.hpp"
#include "scene_schema/json_text.hpp"
#include "stereoscene/support/asset_dir.hpp"
#include "stereoscene/support/atomic_file.hpp"
#include "stereoscene/support/file_read.hpp"

namespace cloud_analysis::geometry {

struct SegmentClassifier::Impl {
    cv::Ptr<cv::ml::RTrees> trees;
    double vote_threshold = 0.5;
};

SegmentClassifier::SegmentClassifier(std::unique_ptr<Impl> impl) : impl_(std::move(impl)) {}
SegmentClassifier::~SegmentClassifier() = default;

namespace {

/// The manifest's trees file: a plain name in the manifest's folder.
std::filesystem::path model_file(const nlohmann::json& doc, const std::filesystem::path& manifest,
                                 const std::function<std::runtime_error(std::string)>& fail) {
    const auto model = doc.find("model");
    if (model == doc.end() || !model->is_string()) throw fail("/model: must be a file name");
    const std::filesystem::path name(model->get<std::string>());
    if (name.empty() || name.has_parent_path() || name.is_absolute()) {
        throw fail("/model: must name a file beside the manifest");
    }
    return manifest.parent_path() / name;
}

void check_manifest(const nlohmann::json& doc, SegmentTarget target,
                    const std::function<std::runtime_error(std::string)>& fail) {
    const std::string format = "stereoscene-" + target_name(target) + "-classifier";
    if (const auto problem = scene_schema::format_header_problem(doc, format, 1)) {
        throw fail(*problem);
    }
    const auto features = doc.find("features");
    std::vector<std::string> expected(kSegmentFeatureNames.begin(), kSegmentFeatureNames.end());
    if (features == doc.end() || !features->is_array() || *features != nlohmann::json(expected)) {
        throw fail("/features: must be the segments' features in order (" +
                   std::to_string(expected.size()) + ": top_m ... disparity_spread)");
    }
    const auto threshold = doc.find("vote_threshold");
    if (threshold == doc.end() || !threshold->is_number() || !(threshold->get<double>() > 0.0) ||
        !(threshold->get<double>() < 1.0)) {
        throw fail("/vote_threshold: must be a number in (0, 1)");
    }
}

}  // namespace

std::string target_name(SegmentTarget target) {
    return target == SegmentTarget::person ? "person" : "vehicle";
}

std::shared_ptr<const SegmentClassifier> SegmentClassifier::load(
    const std::filesystem::path& manifest, SegmentTarget target) {
    const auto fail = [&](const std::string& reason) {
        return std::runtime_error(manifest.string() + ": " + reason);
    };
    nlohmann::json doc;
    try {
        doc = scene_schema::parse_json(stereoscene::support::read_text_input(manifest));
    } catch (const stereoscene::support::FileError& e) {
        throw fail(e.reason());
    } catch (const scene_schema::SchemaError& e) {
        throw fail(e.rule());
    }
    check_manifest(doc, target, fail);
    const std::filesystem::path file = model_file(doc, manifest, fail);
    const auto bad_model = [&](const std::string& reason) {
        return std::runtime_error(file.string() + ": " + reason);
    };
    std::error_code ec;
    if (!std::filesystem::is_regular_file(file, ec)) throw bad_model("no such model file");
    auto impl = std::make_unique<Impl>();
    impl->vote_threshold = doc["vote_threshold"].get<double>();
    try {
        impl->trees = cv::ml::RTrees::load(file.string());
    } catch (const cv::Exception&) {
        throw bad_model("not a trained random trees classifier (cv::ml::RTrees)");
    }
    if (impl->trees.empty() || !impl->trees->isTrained() || !impl->trees->isClassifier()) {
        throw bad_model("not a trained random trees classifier (cv::ml::RTrees)");
    }
    if (impl->trees->getVarCount() != static_cast<int>(kSegmentFeatureNames.size())) {
        throw bad_model("the model reads " + std::to_string(impl->trees->getVarCount()) +
                        " features, the segments have " +
                        std::to_string(kSegmentFeatureNames.size()));
    }
    return std::shared_ptr<const SegmentClassifier>(new SegmentClassifier(std::move(impl)));
}

double SegmentClassifier::vote_threshold() const { return impl_->vote_threshold; }

double SegmentClassifier::votes(const std::vector<float>& features) const {
    const cv::Mat sample(1, static_cast<int>(features.size()), CV_32F,
                         const_cast<float*>(features.data()));
    cv::Mat votes;
    impl_->trees->getVotes(sample, votes, 0);
    // Row 0 names the classes, row 1 counts the trees voting for each.
    double target = 0.0, total = 0.0;
    for (int c = 0; c < votes.cols; ++c) {
        const double n = votes.at<int>(1, c);
        total += n;
        if (votes.at<int>(0, c) == 1) target += n;
    }
    return total > 0.0 ? target / total : 0.0;
}

std::vector<float> segment_features(const Segment& s, double fx_px, double fy_px) {
    const double area = static_cast<double>(s.pixels) * s.depth_m * s.depth_m / (fx_px * fy_px);
    const double values[] = {s.top_m,
                             s.top_q25_m,
                             s.low_m,
                             s.width_m,
                             s.thickness_m,
                             s.depth_m,
                             s.near_m,
                             s.far_m,
                             s.green,
                             s.occluded,
                             s.tall ? 1.0 : 0.0,
                             s.horizontal_edges,
                             s.top_m - s.top_q25_m,
                             s.far_m - s.near_m,
                             area,
                             s.chroma_r,
                             s.chroma_g,
                             s.chroma_b,
                             s.fill,
                             s.luma,
                             s.luma_cv,
                             s.grad,
                             s.rough_h,
                             s.rough_v,
                             s.disparity_spread};
    static_assert(std::size(values) == kSegmentFeatureNames.size());
    return std::vector<float>(std::begin(values), std::end(values));
}

std::filesystem::path default_segment_classifier_path(SegmentTarget target) {
    return stereoscene::support::asset_dir() / "classifiers" /
           (target_name(target) + "-segments.json");
}

}  // namespace cloud_analysis::geometry
