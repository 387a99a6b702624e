#include "evaluate.hpp"

#include <algorithm>
#include <iostream>
#include <optional>
#include <stdexcept>
#include <vector>

#include <nlohmann/json.hpp>
#include <scene_schema/entities.hpp>

#include "cloud_analysis/cloud/semantic.hpp"
#include "cloud_analysis/evaluation/diagnosis.hpp"
#include "cloud_analysis/evaluation/entity_eval.hpp"
#include "cloud_analysis/evaluation/evaluate.hpp"
#include "cloud_analysis/evaluation/kitti_labels.hpp"
#include "cloud_analysis/evaluation/report.hpp"
#include "cloud_analysis/io/io.hpp"
#include "cloud_analysis/stereo/calibration.hpp"
#include "cloud_analysis/stereo/disparity.hpp"
#include "evaluate_labels_2d.hpp"
#include "output.hpp"

namespace cloud_analysis::app {
namespace {

namespace fs = std::filesystem;

/// Input paths after applying the KITTI layout defaults.
struct ResolvedPaths {
    fs::path gt_disparity, instance, calib, visibility;
};

bool entity_mode(const EvaluateArgs& args) {
    return !args.reference.empty() || !args.labels.empty();
}

/// The entity-to-entity mode's paths (--reference or --labels); throws when a file is missing.
ResolvedPaths resolve_entity_mode(const EvaluateArgs& args, ResolvedPaths p) {
    std::vector<fs::path> inputs = {args.entities,
                                    args.reference.empty() ? args.labels : args.reference};
    if (args.min_visible_pixels > 0) {
        if (p.instance.empty() && !args.kitti_root.empty() && !args.frame.empty()) {
            p.instance = args.kitti_root / "instance" / (args.frame + ".png");
        }
        if (p.instance.empty() || args.reference.empty()) {
            throw CLI::ValidationError("--min-visible-pixels",
                                       "needs --reference and --instance (or --kitti-root "
                                       "and --frame)");
        }
        inputs.push_back(p.instance);
    }
    if (args.min_visible_fraction > 0.0) {
        if (p.visibility.empty() && !args.kitti_root.empty() && !args.frame.empty()) {
            p.visibility = args.kitti_root / "visibility" / (args.frame + ".json");
        }
        if (p.visibility.empty() || args.reference.empty()) {
            throw CLI::ValidationError("--min-visible-fraction",
                                       "needs --reference and --visibility (or --kitti-root "
                                       "and --frame)");
        }
        inputs.push_back(p.visibility);
    }
    if (!args.disparity.empty()) {
        if (p.gt_disparity.empty() && !args.kitti_root.empty() && !args.frame.empty()) {
            p.gt_disparity = args.kitti_root / "disp_occ_0" / (args.frame + ".png");
        }
        if (p.gt_disparity.empty()) {
            throw CLI::ValidationError("--gt-disparity", "required with --disparity");
        }
        inputs.push_back(args.disparity);
        inputs.push_back(p.gt_disparity);
    }
    require_input_files(inputs, "evaluate");
    return p;
}

/// The KITTI mode's paths (the layout's defaults); throws when a file is missing.
ResolvedPaths resolve_kitti_mode(const EvaluateArgs& args, ResolvedPaths p) {
    if (!args.kitti_root.empty()) {
        if (args.frame.empty()) throw CLI::ValidationError("--frame", "required with --kitti-root");
        const std::string png = args.frame + ".png";
        if (p.gt_disparity.empty()) p.gt_disparity = args.kitti_root / "disp_occ_0" / png;
        if (p.instance.empty()) p.instance = args.kitti_root / "instance" / png;
        if (p.calib.empty()) p.calib = args.kitti_root / "calib" / "calib_cam_to_cam.txt";
    }
    if (args.entities.empty() && args.disparity.empty()) {
        throw CLI::ValidationError("--entities/--disparity", "give at least one to evaluate");
    }
    if (p.gt_disparity.empty()) {
        throw CLI::ValidationError("--gt-disparity", "required (or --kitti-root and --frame)");
    }
    if (!args.entities.empty() && (p.instance.empty() || p.calib.empty())) {
        throw CLI::ValidationError("--instance/--calib",
                                   "required to score entities (or --kitti-root and --frame)");
    }
    std::vector<fs::path> inputs = {p.gt_disparity};
    if (!args.disparity.empty()) inputs.push_back(args.disparity);
    if (!args.entities.empty()) {
        inputs.push_back(args.entities);
        inputs.push_back(p.instance);
        inputs.push_back(p.calib);
    }
    require_input_files(inputs, "evaluate");
    return p;
}

ResolvedPaths resolve(const EvaluateArgs& args) {
    ResolvedPaths p{args.gt_disparity, args.instance, args.calib, args.visibility};
    check_labels_2d_flags(args);
    if (!args.labels_2d.empty()) return p;
    if (!args.reference.empty() && !args.labels.empty()) {
        throw CLI::ValidationError("--reference/--labels", "give one reference, not both");
    }
    if (entity_mode(args) && args.entities.empty()) {
        throw CLI::ValidationError("--entities", "required with --reference or --labels");
    }
    if (args.bars.any() && !entity_mode(args)) {
        throw CLI::ValidationError("--require-recall/--max-*", "bars need --reference or --labels");
    }
    try {
        args.entity_eval.validate();
        args.bars.validate();
    } catch (const std::invalid_argument& e) {
        throw CLI::ValidationError("evaluate", e.what());
    }
    return entity_mode(args) ? resolve_entity_mode(args, p) : resolve_kitti_mode(args, p);
}

/// The KITTI mode's car-matching flags.
void add_car_flags(CLI::App* sub, EvaluateArgs& args) {
    sub->add_option("--max-range", args.max_range_m, "Cars farther than this are ignored, metres")
        ->check(CLI::PositiveNumber);
    sub->add_option("--min-gt-pixels", args.min_gt_pixels,
                    "GT cars with fewer GT disparity pixels are not owed (recall)")
        ->check(CLI::NonNegativeNumber);
    sub->add_option("--occluder-gap", args.occluder_gap_m,
                    "GT car depths split at gaps larger than this; nearer groups than the car's "
                    "own surface are occluders inside its mask and dropped, metres (0 = keep "
                    "every GT pixel)")
        ->check(CLI::NonNegativeNumber)
        ->capture_default_str();
    sub->add_option("--fallback-max-points", args.fallback_max_points,
                    "GT cars with at most this many GT points are matched by KITTI's 2D "
                    "criterion (projected box vs mask rectangle, IoU >= 0.5; -1 = never)")
        ->check(CLI::Range(-1, 1 << 30))
        ->capture_default_str();
}

/// The entity-to-entity mode's flags.
void add_entity_flags(CLI::App* sub, EvaluateArgs& args) {
    const std::string ee = "Entity-to-entity (--reference or --labels)";
    sub->add_option("--reference", args.reference,
                    "reference entity file (e.g. a rendered scene's truth): score --entities "
                    "against it per class and distance bin")
        ->group(ee);
    sub->add_option("--labels", args.labels,
                    "KITTI label_2 file as the reference (y = box bottom; DontCare/Misc ignored)")
        ->group(ee);
    auto& o = args.entity_eval;
    sub->add_option("--match-distance", o.max_match_distance_m,
                    "largest bird's-eye centre distance of a match, metres")
        ->check(CLI::PositiveNumber)
        ->capture_default_str()
        ->group(ee);
    sub->add_option("--eval-range", o.max_range_m,
                    "entities farther than this (bird's-eye) are ignored, metres")
        ->check(CLI::PositiveNumber)
        ->capture_default_str()
        ->group(ee);
    sub->add_option("--iou-threshold", o.iou_threshold, "BEV IoU of a good match, (0, 1]")
        ->check(CLI::Range(1e-9, 1.0))
        ->capture_default_str()
        ->group(ee);
    sub->add_option("--stuff-overlap", o.stuff_overlap,
                    "a stuff entity lying at least this share inside a reference thing is "
                    "spurious, (0, 1]")
        ->check(CLI::Range(1e-9, 1.0))
        ->capture_default_str()
        ->group(ee);
    sub->add_option("--min-visible-pixels", args.min_visible_pixels,
                    "reference things with fewer pixels in --instance (scene-render sensors' "
                    "instance image of the reference) are not scored, like KITTI's DontCare "
                    "(0 = score all)")
        ->check(CLI::NonNegativeNumber)
        ->capture_default_str()
        ->group(ee);
    sub->add_option("--min-visible-fraction", args.min_visible_fraction,
                    "reference things of which less than this share is visible (visible / "
                    "unoccluded pixels in --visibility, from scene-render sensors) are not "
                    "scored, like KITTI's occlusion level 2 in the moderate setting (0 = score "
                    "all)")
        ->check(CLI::Range(0.0, 1.0))
        ->capture_default_str()
        ->group(ee);
    sub->add_option("--visibility", args.visibility,
                    "visibility JSON of the reference (overrides "
                    "<kitti-root>/visibility/<frame>.json)")
        ->group(ee);
}

/// The pass bars' flags.
void add_bar_flags(CLI::App* sub, EvaluateArgs& args) {
    const std::string bg = "Bars (exit 3 when one is missed; off unless given)";
    auto& b = args.bars;
    sub->add_option("--bar-class", b.class_name, "class the bars apply to")
        ->capture_default_str()
        ->group(bg);
    sub->add_option("--bar-range", b.max_range_m, "bars use the bins up to this edge, metres")
        ->check(CLI::IsMember({10.0, 20.0, 30.0, 50.0}))
        ->capture_default_str()
        ->group(bg);
    sub->add_option("--require-recall", b.require_recall, "minimum recall, [0, 1]")
        ->check(CLI::Range(0.0, 1.0))
        ->group(bg);
    sub->add_option("--max-spurious", b.max_spurious, "most unmatched entities of the class")
        ->check(CLI::NonNegativeNumber)
        ->group(bg);
    sub->add_option("--max-stuff-on-things", b.max_stuff_on_things,
                    "most stuff-class entities sitting on a reference thing (any class)")
        ->check(CLI::NonNegativeNumber)
        ->group(bg);
    sub->add_option("--max-median-centre-error", b.max_median_centre_error_m,
                    "largest median 3D centre error, metres")
        ->check(CLI::NonNegativeNumber)
        ->group(bg);
    sub->add_option("--max-median-heading-error", b.max_median_heading_error_deg,
                    "largest median heading error (mod 180), degrees")
        ->check(CLI::NonNegativeNumber)
        ->group(bg);
    sub->add_option("--min-good-iou-fraction", b.min_good_iou_fraction,
                    "least share of reference entities matched with BEV IoU >= --iou-threshold")
        ->check(CLI::Range(0.0, 1.0))
        ->group(bg);
}

}  // namespace

CLI::App* add_evaluate_command(CLI::App& app, EvaluateArgs& args) {
    CLI::App* sub = app.add_subcommand(
        "evaluate",
        "Score a run against KITTI ground truth: disparity (D1-all, EPE, density) and "
        "car entities (footprint matching, recall and precision within range)");
    sub->add_option("--entities", args.entities,
                    "Entity JSON file to score (with --labels-2d also a batch folder of them)");
    sub->add_option("--disparity", args.disparity, "Our disparity, KITTI 16-bit PNG");
    sub->add_option("--kitti-root", args.kitti_root,
                    "KITTI folder (disp_occ_0/, instance/, calib/calib_cam_to_cam.txt)");
    sub->add_option("--frame", args.frame, "Frame id within --kitti-root, e.g. 000000_10");
    sub->add_option("--gt-disparity", args.gt_disparity, "Ground-truth disparity PNG (overrides)");
    sub->add_option("--instance", args.instance, "Ground-truth instance PNG (overrides)");
    sub->add_option("--calib", args.calib,
                    "Calibration file (overrides; with --labels: where the entities' camera sits "
                    "in the labels' camera 0, t of P2)");
    sub->add_option("--json", args.json, "Also write the scores as JSON ('-' = stdout)");
    add_car_flags(sub, args);
    add_entity_flags(sub, args);
    add_bar_flags(sub, args);
    add_labels_2d_flags(sub, args);
    sub->footer(
        "Exit codes: 0 ok, 1 failure, 2 usage error, 3 a bar was missed (one stderr line "
        "each).");
    return sub;
}

namespace {

/// Where the entities' camera sits in the labels' camera 0: from --calib, else from what the
/// entity file records (a warning when neither says).
LabelFrame labels_frame(const EvaluateArgs& args, const scene_schema::EntityDocument& estimate) {
    if (!args.calib.empty()) return label_frame_of(load_calibration(args.calib));
    if (const auto frame = label_frame_of(estimate)) return *frame;
    std::cerr << "cloud-analysis: warning: " << args.entities.string()
              << ": the file does not say where its camera sits in KITTI's camera 0: the labels "
                 "are compared in their own frame (give --calib)\n";
    return {};
}

/// The entity file, its reference and the references' visibility, read.
EntityComparison read_comparison(const EvaluateArgs& args, const ResolvedPaths& paths) {
    EntityComparison c;
    c.entities_file = args.entities.string();
    const scene_schema::EntityDocument estimate = scene_schema::read_file(args.entities);
    c.estimate = estimate.entities;
    if (!args.labels.empty()) {
        c.reference = entities_from_kitti_labels(load_kitti_labels(args.labels),
                                                 labels_frame(args, estimate));
        c.reference_file = args.labels.string();
    } else {
        c.reference = scene_schema::read_file(args.reference).entities;
        c.reference_file = args.reference.string();
    }
    c.min_visible_pixels = args.min_visible_pixels;
    if (args.min_visible_pixels > 0) {
        c.visible_pixels = visible_instance_pixels(paths.instance, c.reference);
    }
    c.min_visible_fraction = args.min_visible_fraction;
    if (args.min_visible_fraction > 0.0) {
        c.visibility = load_reference_visibility(paths.visibility, c.reference, args.entity_eval);
    }
    return c;
}

/// Disparity of --disparity scored against the ground truth.
void evaluate_disparity(const EvaluateArgs& args, const ResolvedPaths& paths,
                        EvaluationReport& report) {
    const DisparityMap gt_disparity = read_kitti_disparity(paths.gt_disparity);
    const DisparityMap estimate = read_kitti_disparity(args.disparity);
    if (estimate.width_px != gt_disparity.width_px ||
        estimate.height_px != gt_disparity.height_px) {
        throw std::runtime_error("cannot evaluate disparity: size differs from the ground truth (" +
                                 args.disparity.string() + ")");
    }
    report_disparity(score_disparity(estimate, gt_disparity), args.disparity.string(), report);
}

/// Car entities of --entities scored against the instance image's cars.
void evaluate_car_entities(const EvaluateArgs& args, const ResolvedPaths& paths,
                           EvaluationReport& report) {
    const scene_schema::EntityDocument doc = scene_schema::read_file(args.entities);
    const Calibration calib = load_calibration(paths.calib);
    GtCarOptions gt_options;
    gt_options.occluder_gap_m = args.occluder_gap_m;
    const std::vector<GtCar> gt =
        load_gt_cars(paths.instance, paths.gt_disparity, calib.camera, gt_options);
    CarMatchOptions options;
    options.max_range_m = args.max_range_m;
    options.min_gt_pixels = static_cast<std::size_t>(args.min_gt_pixels);
    const bool with_fallback = args.fallback_max_points >= 0;
    options.fallback_max_points = static_cast<std::size_t>(std::max(0, args.fallback_max_points));
    const InstanceImage image = load_instance_image(paths.instance, load_palette("cityscapes"));
    report_cars(args.entities.string(), doc.entities, gt, options, gt_options,
                with_fallback ? &calib.camera : nullptr, report, &image, &calib.camera);
    report_ground_plane(doc, report);
}

}  // namespace

int run_evaluate(const EvaluateArgs& args) {
    const ResolvedPaths paths = resolve(args);
    EvaluationReport report;
    if (!args.frame.empty()) report.json["frame"] = args.frame;
    if (!args.disparity.empty()) evaluate_disparity(args, paths, report);
    if (!args.labels_2d.empty()) {
        evaluate_labels_2d(args, report);
    } else if (entity_mode(args)) {
        report_entities(read_comparison(args, paths), args.entity_eval, args.bars, report);
    } else if (!args.entities.empty()) {
        evaluate_car_entities(args, paths, report);
    }
    const std::string json_text = report.json.dump(2) + "\n";
    const bool json_to_stdout = args.json == "-";
    (json_to_stdout ? std::cerr : std::cout) << report.table;
    if (json_to_stdout) {
        std::cout << json_text;
    } else if (!args.json.empty()) {
        stereoscene::support::write_file_atomic(args.json, json_text);
    }
    for (const auto& m : report.missed_bars)
        std::cerr << "cloud-analysis: bar missed: " << m << "\n";
    return report.missed_bars.empty() ? 0 : kExitBarMissed;
}

}  // namespace cloud_analysis::app
