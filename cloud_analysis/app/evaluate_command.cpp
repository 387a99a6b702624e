#include "evaluate_command.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <iostream>
#include <optional>
#include <sstream>
#include <stdexcept>

#include <nlohmann/json.hpp>
#include <scene_schema/entities.hpp>

#include "cloud_analysis/evaluation/entity_eval.hpp"
#include "cloud_analysis/evaluation/evaluate.hpp"
#include "cloud_analysis/evaluation/kitti_labels.hpp"
#include "cloud_analysis/io/io.hpp"
#include "cloud_analysis/stereo/calibration.hpp"
#include "cloud_analysis/stereo/disparity.hpp"

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

ResolvedPaths resolve(const EvaluateArgs& args) {
    ResolvedPaths p{args.gt_disparity, args.instance, args.calib, args.visibility};
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
    if (entity_mode(args)) {
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
        for (const auto& f : inputs) {
            std::error_code ec;
            if (f != "-" && !fs::is_regular_file(f, ec)) {
                throw std::runtime_error("cannot evaluate: no such file (" + f.string() + ")");
            }
        }
        return p;
    }
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
    for (const auto& f : inputs) {
        std::error_code ec;
        if (f != "-" && !fs::is_regular_file(f, ec)) {
            throw std::runtime_error("cannot evaluate: no such file (" + f.string() + ")");
        }
    }
    return p;
}

std::string fixed(double v, int decimals) {
    char buf[64];
    std::snprintf(buf, sizeof buf, "%.*f", decimals, v);
    return buf;
}

}  // namespace

CLI::App* add_evaluate_command(CLI::App& app, EvaluateArgs& args) {
    CLI::App* sub = app.add_subcommand(
        "evaluate",
        "Score a run against KITTI ground truth: disparity (D1-all, EPE, density) and "
        "car entities (footprint matching, recall and precision within range)");
    sub->add_option("--entities", args.entities, "Entity JSON file to score (car entities)");
    sub->add_option("--disparity", args.disparity, "Our disparity, KITTI 16-bit PNG");
    sub->add_option("--kitti-root", args.kitti_root,
                    "KITTI folder (disp_occ_0/, instance/, calib/calib_cam_to_cam.txt)");
    sub->add_option("--frame", args.frame, "Frame id within --kitti-root, e.g. 000000_10");
    sub->add_option("--gt-disparity", args.gt_disparity, "Ground-truth disparity PNG (overrides)");
    sub->add_option("--instance", args.instance, "Ground-truth instance PNG (overrides)");
    sub->add_option("--calib", args.calib, "Calibration file (overrides)");
    sub->add_option("--json", args.json, "Also write the scores as JSON ('-' = stdout)");
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
    sub->footer(
        "Exit codes: 0 ok, 1 failure, 2 usage error, 3 a bar was missed (one stderr line "
        "each).");
    return sub;
}

namespace {

std::string bin_row(const std::string& cls, const std::string& bin, const ClassBinScore& s,
                    bool thing) {
    char line[320];
    if (!thing) {
        std::snprintf(line, sizeof line, "  %-12s %-6s %4s %4zu %4s %4s %4zu  (stuff on things)\n",
                      cls.c_str(), bin.c_str(), "-", s.estimate, "-", "-", s.spurious);
        return line;
    }
    std::vector<double> dw, dh, dl;
    for (const auto& e : s.size_errors_m) {
        dw.push_back(std::abs(e.x()));
        dh.push_back(std::abs(e.y()));
        dl.push_back(std::abs(e.z()));
    }
    std::snprintf(line, sizeof line,
                  "  %-12s %-6s %4zu %4zu %4zu %4zu %4zu %6.3f %6.3f %7.2f %7.1f %5.2f %5.2f "
                  "%4zu/%-4zu %5.2f %5.2f %5.2f\n",
                  cls.c_str(), bin.c_str(), s.reference, s.estimate, s.matched, s.missed,
                  s.spurious, s.recall(), s.precision(), median(s.centre_errors_m),
                  median(s.heading_errors_deg), median(s.bev_ious), median(s.ious_3d), s.good_iou,
                  s.reference, median(dw), median(dh), median(dl));
    return line;
}

nlohmann::json bin_json(const ClassBinScore& s) {
    std::vector<double> dw, dh, dl;
    for (const auto& e : s.size_errors_m) {
        dw.push_back(std::abs(e.x()));
        dh.push_back(std::abs(e.y()));
        dl.push_back(std::abs(e.z()));
    }
    return {{"reference", s.reference},
            {"estimate", s.estimate},
            {"matched", s.matched},
            {"missed", s.missed},
            {"spurious", s.spurious},
            {"recall", s.recall()},
            {"precision", s.precision()},
            {"good_iou", s.good_iou},
            {"good_iou_fraction", s.good_iou_fraction()},
            {"median_centre_error_m", median(s.centre_errors_m)},
            {"median_heading_error_deg", median(s.heading_errors_deg)},
            {"median_bev_iou", median(s.bev_ious)},
            {"median_iou_3d", median(s.ious_3d)},
            {"median_abs_size_error_m", {{"W", median(dw)}, {"H", median(dh)}, {"L", median(dl)}}}};
}

/// Entity-to-entity scores into table and JSON; returns the missed bars.
std::vector<std::string> evaluate_entity_files(const EvaluateArgs& args, const ResolvedPaths& paths,
                                               std::ostream& table, nlohmann::json& out) {
    const scene_schema::EntityDocument doc = scene_schema::read_file(args.entities);
    std::vector<scene_schema::Entity> reference;
    std::string reference_name;
    if (!args.labels.empty()) {
        reference = entities_from_kitti_labels(load_kitti_labels(args.labels));
        reference_name = args.labels.string();
    } else {
        reference = scene_schema::read_file(args.reference).entities;
        reference_name = args.reference.string();
    }
    std::vector<bool> ignored(reference.size(), false);
    std::vector<std::size_t> visible;
    if (args.min_visible_pixels > 0) {
        visible = visible_instance_pixels(paths.instance, reference);
        for (std::size_t i = 0; i < visible.size(); ++i) {
            if (visible[i] < static_cast<std::size_t>(args.min_visible_pixels)) ignored[i] = true;
        }
    }
    std::vector<std::optional<ReferenceVisibility>> visibility;
    if (args.min_visible_fraction > 0.0) {
        visibility = load_reference_visibility(paths.visibility, reference, args.entity_eval);
        for (std::size_t i = 0; i < visibility.size(); ++i) {
            if (visibility[i] && visibility[i]->visible_fraction < args.min_visible_fraction)
                ignored[i] = true;
        }
    }
    const EntityEvaluation ev =
        evaluate_entities(reference, doc.entities, args.entity_eval, ignored);
    // The same scores with every reference scored, so the filter hides nothing.
    const EntityEvaluation unfiltered =
        evaluate_entities(reference, doc.entities, args.entity_eval);
    const auto& o = ev.options;
    table << "entities " << args.entities.string() << " vs reference " << reference_name << "\n"
          << "  matching: same class, greedy by bird's-eye centre distance <= "
          << fixed(o.max_match_distance_m, 2) << " m; range <= " << fixed(o.max_range_m, 0)
          << " m; good = BEV IoU >= " << fixed(o.iou_threshold, 2) << "\n"
          << "  class        bin     ref  est  hit miss spur recall  prec. centre_m head_deg "
             "bev   3d   good      |dW|  |dH|  |dL|\n";
    nlohmann::json classes = nlohmann::json::object();
    for (const auto& c : ev.classes) {
        nlohmann::json bins = nlohmann::json::object();
        for (std::size_t i = 0; i < c.bins.size(); ++i) {
            const std::string name = distance_bin_name(static_cast<int>(i));
            bins[name] = bin_json(c.bins[i]);
            if (c.bins[i].reference + c.bins[i].estimate > 0 || i + 1 == c.bins.size()) {
                table << bin_row(c.class_name, name, c.bins[i], c.thing);
            }
        }
        classes[c.class_name] = {{"thing", c.thing}, {"bins", bins}};
    }
    nlohmann::json matches = nlohmann::json::array();
    for (const auto& m : ev.matches) {
        matches.push_back(
            {{"reference", reference[m.reference].id},
             {"estimate", doc.entities[m.estimate].id},
             {"class", reference[m.reference].class_name},
             {"range_m", bev_range_m(reference[m.reference])},
             {"centre_error_m", m.centre_error_m},
             {"bev_centre_error_m", m.bev_centre_error_m},
             {"size_error_m", {m.size_error_m.x(), m.size_error_m.y(), m.size_error_m.z()}},
             {"heading_error_deg", m.heading_error_rad * 180.0 / 3.14159265358979},
             {"bev_iou", m.bev_iou},
             {"iou_3d", m.iou_3d}});
    }
    nlohmann::json missed = nlohmann::json::array(), spurious = nlohmann::json::array();
    for (const auto r : ev.missed) missed.push_back(reference[r].id);
    for (const auto e : ev.spurious) spurious.push_back(doc.entities[e].id);
    if (!ev.missed.empty()) table << "  missed:   " << missed.dump() << "\n";
    if (!ev.spurious.empty()) table << "  spurious: " << spurious.dump() << "\n";
    nlohmann::json not_scored = nlohmann::json::array();
    for (const auto r : ev.ignored) {
        nlohmann::json row = {{"id", reference[r].id}};
        if (!visible.empty()) row["visible_pixels"] = visible[r];
        if (!visibility.empty() && visibility[r]) {
            row["visible_px"] = visibility[r]->visible_px;
            row["unoccluded_px"] = visibility[r]->unoccluded_px;
            row["visible_fraction"] = visibility[r]->visible_fraction;
        }
        not_scored.push_back(row);
    }
    const ClassBinScore all = unfiltered.within(args.bars.class_name, args.bars.max_range_m);
    nlohmann::json unfiltered_json = {{"class", args.bars.class_name},
                                      {"max_range_m", args.bars.max_range_m},
                                      {"reference", all.reference},
                                      {"matched", all.matched},
                                      {"recall", all.recall()},
                                      {"good_iou", all.good_iou},
                                      {"good_iou_fraction", all.good_iou_fraction()}};
    if (!ev.ignored.empty()) {
        table << "  not scored (";
        if (args.min_visible_pixels > 0) table << "< " << args.min_visible_pixels << " visible px";
        if (args.min_visible_pixels > 0 && args.min_visible_fraction > 0.0) table << " or ";
        if (args.min_visible_fraction > 0.0)
            table << "visible fraction < " << fixed(args.min_visible_fraction, 2);
        table << "): " << not_scored.dump() << "\n";
        table << "  unfiltered (every reference scored): " << args.bars.class_name << " within "
              << fixed(args.bars.max_range_m, 0) << " m recall " << all.matched << "/"
              << all.reference << " = " << fixed(all.recall(), 3)
              << ", BEV IoU >= " << fixed(o.iou_threshold, 2) << " for " << all.good_iou << "/"
              << all.reference << "\n";
    }

    std::vector<std::string> missed_bars;
    nlohmann::json bars = nlohmann::json::object();
    if (args.bars.any()) {
        missed_bars = check_bars(ev, args.bars);
        const ClassBinScore s = ev.within(args.bars.class_name, args.bars.max_range_m);
        table << "  bars (" << args.bars.class_name << " within " << fixed(args.bars.max_range_m, 0)
              << " m): recall " << fixed(s.recall(), 3) << ", spurious " << s.spurious
              << ", stuff on things " << ev.stuff_on_things(args.bars.max_range_m)
              << ", median centre error " << fixed(median(s.centre_errors_m), 3)
              << " m, median heading error " << fixed(median(s.heading_errors_deg), 2)
              << " deg, BEV IoU >= " << fixed(o.iou_threshold, 2) << " for " << s.good_iou << "/"
              << s.reference << ": " << (missed_bars.empty() ? "PASS" : "FAIL") << "\n";
        bars = {{"class", args.bars.class_name},
                {"max_range_m", args.bars.max_range_m},
                {"pass", missed_bars.empty()},
                {"missed", missed_bars}};
    }
    out["entities"] = {{"entities_file", args.entities.string()},
                       {"reference_file", reference_name},
                       {"max_match_distance_m", o.max_match_distance_m},
                       {"max_range_m", o.max_range_m},
                       {"iou_threshold", o.iou_threshold},
                       {"stuff_overlap", o.stuff_overlap},
                       {"classes", classes},
                       {"matches", matches},
                       {"missed", missed},
                       {"spurious", spurious},
                       {"min_visible_pixels", args.min_visible_pixels},
                       {"min_visible_fraction", args.min_visible_fraction},
                       {"not_scored", not_scored},
                       {"unfiltered", unfiltered_json}};
    if (args.bars.any()) out["bars"] = bars;
    return missed_bars;
}

}  // namespace

int run_evaluate(const EvaluateArgs& args) {
    const ResolvedPaths paths = resolve(args);
    nlohmann::json out = nlohmann::json::object();
    if (!args.frame.empty()) out["frame"] = args.frame;
    std::ostringstream table;
    std::vector<std::string> missed_bars;

    if (!args.disparity.empty()) {
        const DisparityMap gt_disparity = read_kitti_disparity(paths.gt_disparity);
        const DisparityMap estimate = read_kitti_disparity(args.disparity);
        if (estimate.width_px != gt_disparity.width_px ||
            estimate.height_px != gt_disparity.height_px) {
            throw std::runtime_error(
                "cannot evaluate disparity: size differs from the ground truth (" +
                args.disparity.string() + ")");
        }
        const DisparityScore s = score_disparity(estimate, gt_disparity);
        out["disparity"] = {{"file", args.disparity.string()},
                            {"gt_pixels", s.gt_pixels},
                            {"est_pixels", s.est_pixels},
                            {"d1_all", s.d1_all},
                            {"d1_valid", s.d1_valid},
                            {"epe_px", s.epe_px},
                            {"density", s.density}};
        table << "disparity   D1-all " << fixed(100.0 * s.d1_all, 2) << " %   D1-valid "
              << fixed(100.0 * s.d1_valid, 2) << " %   EPE " << fixed(s.epe_px, 3)
              << " px   density " << fixed(100.0 * s.density, 1) << " %   (" << s.gt_pixels
              << " GT px)\n";
    }

    if (entity_mode(args)) {
        missed_bars = evaluate_entity_files(args, paths, table, out);
    } else if (!args.entities.empty()) {
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
        options.fallback_max_points =
            static_cast<std::size_t>(std::max(0, args.fallback_max_points));
        const CarEvaluation ev =
            evaluate_cars(doc.entities, gt, options, with_fallback ? &calib.camera : nullptr);

        nlohmann::json cars = nlohmann::json::array();
        table << "cars within " << fixed(options.max_range_m, 0)
              << " m (GT owed: >= " << options.min_gt_pixels
              << " GT disparity px of the car's own surface; occluder gap "
              << fixed(gt_options.occluder_gap_m, 2) << " m)\n";
        table << "  GT inst   pixels occluder  range_m  matched_entity  rule  inside  iou_2d  "
                 "centre_dist_m\n";
        for (std::size_t g = 0; g < gt.size(); ++g) {
            const GtCar& car = gt[g];
            const CarMatch* match = nullptr;
            for (const auto& m : ev.matches) {
                if (m.gt == g) match = &m;
            }
            const bool no_points = car.pixel_count == 0;
            const bool in_range = !no_points && car.range_m() <= options.max_range_m;
            const bool owed = in_range && car.pixel_count >= options.min_gt_pixels;
            const char* rule = match ? (match->fallback ? "2d" : "bev") : "";
            nlohmann::json row = {
                {"instance", car.instance},
                {"pixels", car.pixel_count},
                {"occluder_pixels", car.occluder_pixel_count},
                {"mask_pixels", car.image_pixels.size()},
                {"range_m", no_points ? nlohmann::json() : nlohmann::json(car.range_m())},
                {"owed", owed},
                {"entity", match ? doc.entities[match->entity].id : ""},
                {"rule", rule},
                {"inside_fraction", match ? match->inside_fraction : 0.0},
                {"iou_2d", match ? match->iou_2d : 0.0},
                {"centre_distance_m", match ? match->centre_distance_m : 0.0}};
            cars.push_back(row);
            // Cars without points have no range: listed when an entity matched them.
            if (!in_range && !(no_points && match)) continue;
            char line[200];
            std::snprintf(line, sizeof line, "  %7d %8zu %8zu %8s  %-14s %4s %7s %7s %14s%s\n",
                          car.instance, car.pixel_count, car.occluder_pixel_count,
                          no_points ? "-" : fixed(car.range_m(), 1).c_str(),
                          match ? doc.entities[match->entity].id.c_str() : "-", match ? rule : "-",
                          match && !no_points ? fixed(match->inside_fraction, 2).c_str() : "-",
                          match && match->fallback ? fixed(match->iou_2d, 2).c_str() : "-",
                          match && !no_points ? fixed(match->centre_distance_m, 2).c_str() : "-",
                          owed ? "" : "  (not owed)");
            table << line;
        }
        table << "  recall    " << ev.gt_owed_matched << "/" << ev.gt_owed << " = "
              << fixed(100.0 * ev.recall(), 1) << " %\n";
        table << "  precision " << ev.entities_matched << "/" << ev.entities_in_range << " = "
              << fixed(100.0 * ev.precision(), 1) << " %   (scorable: " << ev.entities_matched
              << "/" << ev.entities_in_range - ev.entities_unscorable << " = "
              << fixed(100.0 * ev.precision_scorable(), 1) << " %; " << ev.entities_unscorable
              << " entities lie on GT cars without GT points)\n";
        if (with_fallback) {
            table << "  matched by the 2D fallback (GT cars with <= " << options.fallback_max_points
                  << " GT points, IoU >= " << fixed(options.fallback_min_iou, 2)
                  << "): " << ev.fallback_matched << " of " << ev.entities_matched << "\n";
        } else {
            table << "  2D fallback off\n";
        }
        table << "  mean centre distance " << fixed(ev.mean_centre_distance_m(), 2)
              << " m (entity centre to GT visible-point centroid, bird's-eye)\n";
        out["cars"] = {
            {"entities_file", args.entities.string()},
            {"max_range_m", options.max_range_m},
            {"min_gt_pixels", options.min_gt_pixels},
            {"gt_owed", ev.gt_owed},
            {"gt_owed_matched", ev.gt_owed_matched},
            {"entities_in_range", ev.entities_in_range},
            {"entities_matched", ev.entities_matched},
            {"recall", ev.recall()},
            {"precision", ev.precision()},
            {"entities_unscorable", ev.entities_unscorable},
            {"precision_scorable", ev.precision_scorable()},
            {"occluder_gap_m", gt_options.occluder_gap_m},
            {"fallback_max_points",
             with_fallback ? nlohmann::json(options.fallback_max_points) : nlohmann::json()},
            {"fallback_min_iou", options.fallback_min_iou},
            {"fallback_matched", ev.fallback_matched},
            {"mean_centre_distance_m", ev.mean_centre_distance_m()},
            {"gt_cars", cars}};
        if (doc.extra.contains("ground_plane")) {
            const double h = doc.extra["ground_plane"].value("camera_height_m", 0.0);
            out["ground_plane"] = doc.extra["ground_plane"];
            table << "ground plane: camera " << fixed(h, 3) << " m above it\n";
        }
    }

    const std::string json_text = out.dump(2) + "\n";
    const bool json_to_stdout = args.json == "-";
    (json_to_stdout ? std::cerr : std::cout) << table.str();
    if (json_to_stdout) {
        std::cout << json_text;
    } else if (!args.json.empty()) {
        stereoscene::support::write_file_atomic(args.json, json_text);
    }
    for (const auto& m : missed_bars) std::cerr << "cloud-analysis: bar missed: " << m << "\n";
    return missed_bars.empty() ? 0 : kExitBarMissed;
}

CLI::App* add_export_kitti_command(CLI::App& app, ExportKittiArgs& args) {
    CLI::App* sub = app.add_subcommand(
        "export-kitti",
        "Write an entity file as KITTI object label_2 lines (y = box bottom, alpha, 2D box "
        "from the camera; stuff classes are skipped) so KITTI's tools can score it");
    sub->add_option("entities", args.entities, "entity JSON file")->required();
    sub->add_option("-o,--output", args.output, "label_2 text file ('-' = stdout)")->required();
    sub->add_option("--calib", args.calib,
                    "calibration (KITTI or YAML/JSON) for the 2D boxes; default: the entity "
                    "file's frame.camera, else 2D boxes are -1");
    return sub;
}

int run_export_kitti(const ExportKittiArgs& args) {
    for (const auto& f : {args.entities, args.calib}) {
        std::error_code ec;
        if (!f.empty() && f != "-" && !fs::is_regular_file(f, ec)) {
            throw std::runtime_error("cannot export: no such file (" + f.string() + ")");
        }
    }
    if (args.output != "-") {
        const fs::path folder = fs::path(args.output).parent_path();
        if (!folder.empty() && !fs::is_directory(folder)) {
            throw std::runtime_error("cannot export: no such folder (" + folder.string() + ", -o)");
        }
    }
    const scene_schema::EntityDocument doc = scene_schema::read_file(args.entities);
    std::optional<scene_schema::CameraIntrinsics> camera = doc.frame.camera;
    if (!args.calib.empty()) {
        const StereoCamera c = load_calibration(args.calib).camera;
        scene_schema::CameraIntrinsics k;
        k.width_px = c.width_px > 0 ? c.width_px : (camera ? camera->width_px : 0);
        k.height_px = c.height_px > 0 ? c.height_px : (camera ? camera->height_px : 0);
        k.fx_px = c.fx_px;
        k.fy_px = c.fy_px;
        k.cx_px = c.cx_px;
        k.cy_px = c.cy_px;
        k.baseline_m = c.baseline_m;
        camera = k;
    }
    std::vector<KittiLabel> labels;
    for (const auto& e : doc.entities) {
        if (!kitti_type_of_class(e.class_name)) continue;
        labels.push_back(kitti_label_from_entity(e, camera ? &*camera : nullptr));
    }
    const std::string text = format_kitti_labels(labels);
    if (args.output == "-") {
        std::cout << text;
    } else {
        stereoscene::support::write_file_atomic(args.output, text);
    }
    return 0;
}

}  // namespace cloud_analysis::app
