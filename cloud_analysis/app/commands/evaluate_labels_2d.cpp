#include "evaluate_labels_2d.hpp"

#include <algorithm>
#include <filesystem>
#include <stdexcept>
#include <utility>

#include <scene_schema/entities.hpp>

#include "output.hpp"

namespace cloud_analysis::app {
namespace {

namespace fs = std::filesystem;

/// A labelled frame and its entity file, read once.
struct FrameToScore {
    const FrameLabels2d* labels = nullptr;
    fs::path file;
    scene_schema::EntityDocument estimate;
};

/// The frames to score: --frame, else every labelled frame (a folder of <frame>.json) or the
/// entity file's own frame (one file; the only frame of a one-frame labels file when the file's
/// id is not labelled).
std::vector<FrameToScore> frames_to_score(const EvaluateArgs& args, const Labels2d& labels) {
    auto find = [&](const std::string& id) {
        const FrameLabels2d* f = labels.find(id);
        if (f == nullptr) {
            throw std::runtime_error("cannot evaluate: frame \"" + id + "\" is not labelled (" +
                                     labels.origin + ")");
        }
        return f;
    };
    std::vector<FrameToScore> out;
    if (!fs::is_directory(args.entities)) {
        FrameToScore one{nullptr, args.entities, scene_schema::read_file(args.entities)};
        const std::string id = args.frame.empty() ? one.estimate.frame.id : args.frame;
        one.labels = args.frame.empty() && labels.find(id) == nullptr && labels.frames.size() == 1
                         ? &labels.frames.front()
                         : find(id);
        out.push_back(std::move(one));
        return out;
    }
    std::vector<const FrameLabels2d*> chosen;
    if (!args.frame.empty()) {
        chosen.push_back(find(args.frame));
    } else {
        for (const auto& f : labels.frames) chosen.push_back(&f);
    }
    for (const FrameLabels2d* f : chosen) {
        const fs::path file = args.entities / (f->frame + ".json");
        require_input_files({file}, "evaluate");
        out.push_back({f, file, scene_schema::read_file(file)});
    }
    return out;
}

}  // namespace

void add_labels_2d_flags(CLI::App* sub, EvaluateArgs& args) {
    const std::string g = "2D labels (--labels-2d)";
    auto& o = args.match_2d;
    sub->add_option("--labels-2d", args.labels_2d,
                    "2D boxes drawn on the left image (the project's JSON, or KITTI label_2 "
                    ".txt): score --entities (a file or a batch folder) by projecting each box")
        ->group(g);
    sub->add_option("--min-iou-2d", o.min_iou, "IoU of projected box and label box of a match")
        ->check(CLI::Range(1e-9, 1.0))
        ->capture_default_str()
        ->group(g);
    sub->add_option("--min-box-height", o.min_height_px,
                    "labels shorter than this are not owed (a match to them is not counted), px")
        ->check(CLI::NonNegativeNumber)
        ->capture_default_str()
        ->group(g);
    sub->add_option("--max-occluded", o.max_occluded,
                    "labels more hidden than this (0 seen, 1 partly, 2 largely, 3 unknown) are "
                    "not owed")
        ->check(CLI::Range(0, 3))
        ->capture_default_str()
        ->group(g);
    sub->add_option("--max-truncated", o.max_truncated,
                    "labels more truncated by the image border than this share are not owed")
        ->check(CLI::Range(0.0, 1.0))
        ->capture_default_str()
        ->group(g);
    sub->add_flag("--tracked-only", args.tracked_only,
                  "score only the things a tracker confirmed (entities with a track_id, as "
                  "`track` writes them); other things are left out")
        ->group(g);
    sub->add_option("--max-false-per-frame", args.max_false_per_frame,
                    "bar: most false entities of --bar-class's category a frame, on average")
        ->check(CLI::NonNegativeNumber)
        ->group("Bars (exit 3 when one is missed; off unless given)");
}

void check_labels_2d_flags(const EvaluateArgs& args) {
    if (args.labels_2d.empty()) {
        if (args.max_false_per_frame >= 0.0) {
            throw CLI::ValidationError("--max-false-per-frame", "needs --labels-2d");
        }
        if (args.tracked_only) throw CLI::ValidationError("--tracked-only", "needs --labels-2d");
        return;
    }
    if (args.entities.empty())
        throw CLI::ValidationError("--entities", "required with --labels-2d");
    if (!args.reference.empty() || !args.labels.empty() || !args.disparity.empty()) {
        throw CLI::ValidationError("--labels-2d",
                                   "scores entities alone: not with --reference, --labels or "
                                   "--disparity");
    }
    const auto& b = args.bars;
    if (b.max_spurious >= 0 || b.max_stuff_on_things >= 0 || b.max_median_centre_error_m >= 0.0 ||
        b.max_median_heading_error_deg >= 0.0 || b.min_good_iou_fraction >= 0.0) {
        throw CLI::ValidationError("--labels-2d",
                                   "2D labels take the bars --require-recall and "
                                   "--max-false-per-frame");
    }
    if (!category_of_class(b.class_name)) {
        throw CLI::ValidationError("--bar-class", "\"" + b.class_name +
                                                      "\" is not a vehicle, person or cyclist "
                                                      "class");
    }
    try {
        args.match_2d.validate();
    } catch (const std::invalid_argument& e) {
        throw CLI::ValidationError("--labels-2d", e.what());
    }
    require_input_files({args.labels_2d}, "evaluate");
    if (!fs::is_directory(args.entities)) require_input_files({args.entities}, "evaluate");
}

void evaluate_labels_2d(const EvaluateArgs& args, EvaluationReport& report) {
    const Labels2d labels = load_labels_2d(args.labels_2d);
    Labels2dComparison c;
    c.labels_file = args.labels_2d.string();
    c.entities_source = args.entities.string();
    c.tracked_only = args.tracked_only;
    for (FrameToScore& f : frames_to_score(args, labels)) {
        const fs::path& file = f.file;
        scene_schema::EntityDocument& doc = f.estimate;
        if (!doc.frame.camera) {
            throw std::runtime_error(
                "cannot evaluate: the entity file has no frame.camera to "
                "project its boxes with (" +
                file.string() + ")");
        }
        const auto& cam = *doc.frame.camera;
        if (labels.width_px > 0 &&
            (cam.width_px != labels.width_px || cam.height_px != labels.height_px)) {
            throw std::runtime_error(
                "cannot evaluate: the entities' image is " + std::to_string(cam.width_px) + "x" +
                std::to_string(cam.height_px) + ", the labels' " + std::to_string(labels.width_px) +
                "x" + std::to_string(labels.height_px) + " (" + file.string() + ")");
        }
        if (args.tracked_only) {
            // A thing no track confirmed is a detection the tracker did not take up.
            auto& e = doc.entities;
            e.erase(std::remove_if(e.begin(), e.end(),
                                   [](const scene_schema::Entity& x) {
                                       return !x.track_id &&
                                              category_of_class(x.class_name).has_value();
                                   }),
                    e.end());
        }
        c.scores.push_back(score_frame_2d(doc.entities, cam, *f.labels, args.match_2d));
        c.labels.push_back(*f.labels);
        c.estimate.push_back(std::move(doc.entities));
    }
    Labels2dBars bars;
    bars.category = *category_of_class(args.bars.class_name);
    bars.require_recall = args.bars.require_recall;
    bars.max_false_per_frame = args.max_false_per_frame;
    report_labels_2d(c, args.match_2d, bars, report);
}

}  // namespace cloud_analysis::app
