#include "cloud_analysis/evaluation/report.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <sstream>

#include "cloud_analysis/evaluation/diagnosis.hpp"
#include "stereoscene/support/angles.hpp"
#include "stereoscene/support/number_text.hpp"

using stereoscene::support::kPi;

namespace cloud_analysis {
namespace {

using stereoscene::support::fixed_text;

/// Median absolute size errors along W, H, L, metres.
std::array<double, 3> median_abs_size_errors(const ClassBinScore& s) {
    std::vector<double> dw, dh, dl;
    for (const auto& e : s.size_errors_m) {
        dw.push_back(std::abs(e.x()));
        dh.push_back(std::abs(e.y()));
        dl.push_back(std::abs(e.z()));
    }
    return {median(dw), median(dh), median(dl)};
}

std::string bin_row(const std::string& cls, const std::string& bin, const ClassBinScore& s,
                    bool thing) {
    char line[320];
    if (!thing) {
        std::snprintf(line, sizeof line, "  %-12s %-6s %4s %4zu %4s %4s %4zu  (stuff on things)\n",
                      cls.c_str(), bin.c_str(), "-", s.estimate, "-", "-", s.spurious);
        return line;
    }
    const auto [dw, dh, dl] = median_abs_size_errors(s);
    std::snprintf(line, sizeof line,
                  "  %-12s %-6s %4zu %4zu %4zu %4zu %4zu %6.3f %6.3f %7.2f %7.1f %5.2f %5.2f "
                  "%4zu/%-4zu %5.2f %5.2f %5.2f\n",
                  cls.c_str(), bin.c_str(), s.reference, s.estimate, s.matched, s.missed,
                  s.spurious, s.recall(), s.precision(), median(s.centre_errors_m),
                  median(s.heading_errors_deg), median(s.bev_ious), median(s.ious_3d), s.good_iou,
                  s.reference, dw, dh, dl);
    return line;
}

nlohmann::json bin_json(const ClassBinScore& s) {
    const auto [dw, dh, dl] = median_abs_size_errors(s);
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
            {"median_abs_size_error_m", {{"W", dw}, {"H", dh}, {"L", dl}}}};
}

/// Per reference, whether it is too hidden to be scored.
std::vector<bool> not_owed(const EntityComparison& c) {
    std::vector<bool> ignored(c.reference.size(), false);
    if (c.min_visible_pixels > 0) {
        for (std::size_t i = 0; i < c.visible_pixels.size(); ++i) {
            if (c.visible_pixels[i] < static_cast<std::size_t>(c.min_visible_pixels)) {
                ignored[i] = true;
            }
        }
    }
    if (c.min_visible_fraction > 0.0) {
        for (std::size_t i = 0; i < c.visibility.size(); ++i) {
            if (c.visibility[i] && c.visibility[i]->visible_fraction < c.min_visible_fraction)
                ignored[i] = true;
        }
    }
    return ignored;
}

/// The header and one row per non-empty distance bin of each class; the classes' JSON.
nlohmann::json class_scores(const EntityComparison& c, const EntityEvaluation& ev,
                            std::ostream& table) {
    const auto& o = ev.options;
    table << "entities " << c.entities_file << " vs reference " << c.reference_file << "\n"
          << "  matching: same class, greedy by bird's-eye centre distance <= "
          << fixed_text(o.max_match_distance_m, 2)
          << " m; range <= " << fixed_text(o.max_range_m, 0)
          << " m; good = BEV IoU >= " << fixed_text(o.iou_threshold, 2) << "\n"
          << "  class        bin     ref  est  hit miss spur recall  prec. centre_m head_deg "
             "bev   3d   good      |dW|  |dH|  |dL|\n";
    nlohmann::json classes = nlohmann::json::object();
    for (const auto& cls : ev.classes) {
        nlohmann::json bins = nlohmann::json::object();
        for (std::size_t i = 0; i < cls.bins.size(); ++i) {
            const std::string name = distance_bin_name(static_cast<int>(i));
            bins[name] = bin_json(cls.bins[i]);
            if (cls.bins[i].reference + cls.bins[i].estimate > 0 || i + 1 == cls.bins.size()) {
                table << bin_row(cls.class_name, name, cls.bins[i], cls.thing);
            }
        }
        classes[cls.class_name] = {{"thing", cls.thing}, {"bins", bins}};
    }
    return classes;
}

nlohmann::json matches_json(const EntityComparison& c, const EntityEvaluation& ev) {
    nlohmann::json matches = nlohmann::json::array();
    for (const auto& m : ev.matches) {
        const scene_schema::Entity& ref = c.reference[m.reference];
        matches.push_back(
            {{"reference", ref.id},
             {"estimate", c.estimate[m.estimate].id},
             {"class", ref.class_name},
             {"range_m", bev_range_m(ref)},
             {"centre_error_m", m.centre_error_m},
             {"bev_centre_error_m", m.bev_centre_error_m},
             {"size_error_m", {m.size_error_m.x(), m.size_error_m.y(), m.size_error_m.z()}},
             {"heading_error_deg", m.heading_error_rad * 180.0 / kPi},
             {"bev_iou", m.bev_iou},
             {"iou_3d", m.iou_3d}});
    }
    return matches;
}

nlohmann::json not_scored_json(const EntityComparison& c, const EntityEvaluation& ev) {
    nlohmann::json not_scored = nlohmann::json::array();
    for (const auto r : ev.ignored) {
        nlohmann::json row = {{"id", c.reference[r].id}};
        if (!c.visible_pixels.empty()) row["visible_pixels"] = c.visible_pixels[r];
        if (!c.visibility.empty() && c.visibility[r]) {
            row["visible_px"] = c.visibility[r]->visible_px;
            row["unoccluded_px"] = c.visibility[r]->unoccluded_px;
            row["visible_fraction"] = c.visibility[r]->visible_fraction;
        }
        not_scored.push_back(row);
    }
    return not_scored;
}

/// The line of the references not scored and of the unfiltered scores.
void not_scored_lines(const EntityComparison& c, const nlohmann::json& not_scored,
                      const ClassBinScore& all, const EvalBars& bars, double iou_threshold,
                      std::ostream& table) {
    table << "  not scored (";
    if (c.min_visible_pixels > 0) table << "< " << c.min_visible_pixels << " visible px";
    if (c.min_visible_pixels > 0 && c.min_visible_fraction > 0.0) table << " or ";
    if (c.min_visible_fraction > 0.0)
        table << "visible fraction < " << fixed_text(c.min_visible_fraction, 2);
    table << "): " << not_scored.dump() << "\n";
    table << "  unfiltered (every reference scored): " << bars.class_name << " within "
          << fixed_text(bars.max_range_m, 0) << " m recall " << all.matched << "/" << all.reference
          << " = " << fixed_text(all.recall(), 3) << ", BEV IoU >= " << fixed_text(iou_threshold, 2)
          << " for " << all.good_iou << "/" << all.reference << "\n";
}

/// The bars' line and JSON; the missed bars into report.missed_bars.
void report_bars(const EntityEvaluation& ev, const EvalBars& bars, std::ostream& table,
                 EvaluationReport& report) {
    report.missed_bars = check_bars(ev, bars);
    const ClassBinScore s = ev.within(bars.class_name, bars.max_range_m);
    table << "  bars (" << bars.class_name << " within " << fixed_text(bars.max_range_m, 0)
          << " m): recall " << fixed_text(s.recall(), 3) << ", spurious " << s.spurious
          << ", stuff on things " << ev.stuff_on_things(bars.max_range_m)
          << ", median centre error " << fixed_text(median(s.centre_errors_m), 3)
          << " m, median heading error " << fixed_text(median(s.heading_errors_deg), 2)
          << " deg, BEV IoU >= " << fixed_text(ev.options.iou_threshold, 2) << " for " << s.good_iou
          << "/" << s.reference << ": " << (report.missed_bars.empty() ? "PASS" : "FAIL") << "\n";
    report.json["bars"] = {{"class", bars.class_name},
                           {"max_range_m", bars.max_range_m},
                           {"pass", report.missed_bars.empty()},
                           {"missed", report.missed_bars}};
}

/// One table line per diagnosis ("  why <id>: <reason>") and their JSON.
nlohmann::json diagnosis_lines(const std::vector<Diagnosis>& diagnoses, std::ostream& table) {
    nlohmann::json rows = nlohmann::json::array();
    for (const auto& d : diagnoses) {
        table << "  why " << d.id << " (" << d.kind << "): " << d.reason << "\n";
        rows.push_back({{"id", d.id}, {"kind", d.kind}, {"reason", d.reason}});
    }
    return rows;
}

/// One JSON row per GT car; a table row per GT car in range (or matched without points).
nlohmann::json car_rows(const std::vector<scene_schema::Entity>& entities,
                        const std::vector<GtCar>& gt, const CarEvaluation& ev,
                        const CarMatchOptions& options, std::ostream& table) {
    nlohmann::json cars = nlohmann::json::array();
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
        cars.push_back({{"instance", car.instance},
                        {"pixels", car.pixel_count},
                        {"occluder_pixels", car.occluder_pixel_count},
                        {"mask_pixels", car.image_pixels.size()},
                        {"range_m", no_points ? nlohmann::json() : nlohmann::json(car.range_m())},
                        {"owed", owed},
                        {"entity", match ? entities[match->entity].id : ""},
                        {"rule", rule},
                        {"inside_fraction", match ? match->inside_fraction : 0.0},
                        {"iou_2d", match ? match->iou_2d : 0.0},
                        {"centre_distance_m", match ? match->centre_distance_m : 0.0}});
        // Cars without points have no range: listed when an entity matched them.
        if (!in_range && !(no_points && match)) continue;
        char line[200];
        std::snprintf(line, sizeof line, "  %7d %8zu %8zu %8s  %-14s %4s %7s %7s %14s%s\n",
                      car.instance, car.pixel_count, car.occluder_pixel_count,
                      no_points ? "-" : fixed_text(car.range_m(), 1).c_str(),
                      match ? entities[match->entity].id.c_str() : "-", match ? rule : "-",
                      match && !no_points ? fixed_text(match->inside_fraction, 2).c_str() : "-",
                      match && match->fallback ? fixed_text(match->iou_2d, 2).c_str() : "-",
                      match && !no_points ? fixed_text(match->centre_distance_m, 2).c_str() : "-",
                      owed ? "" : "  (not owed)");
        table << line;
    }
    return cars;
}

}  // namespace

void report_disparity(const DisparityScore& s, const std::string& file, EvaluationReport& report) {
    report.json["disparity"] = {
        {"file", file},        {"gt_pixels", s.gt_pixels}, {"est_pixels", s.est_pixels},
        {"d1_all", s.d1_all},  {"d1_valid", s.d1_valid},   {"epe_px", s.epe_px},
        {"density", s.density}};
    std::ostringstream table;
    table << "disparity   D1-all " << fixed_text(100.0 * s.d1_all, 2) << " %   D1-valid "
          << fixed_text(100.0 * s.d1_valid, 2) << " %   EPE " << fixed_text(s.epe_px, 3)
          << " px   density " << fixed_text(100.0 * s.density, 1) << " %   (" << s.gt_pixels
          << " GT px)\n";
    report.table += table.str();
}

void report_entities(const EntityComparison& c, const EntityEvalOptions& options,
                     const EvalBars& bars, EvaluationReport& report) {
    const EntityEvaluation ev = evaluate_entities(c.reference, c.estimate, options, not_owed(c));
    // The same scores with every reference scored, so the filter hides nothing.
    const EntityEvaluation unfiltered = evaluate_entities(c.reference, c.estimate, options);
    const auto& o = ev.options;
    std::ostringstream table;
    const nlohmann::json classes = class_scores(c, ev, table);
    nlohmann::json missed = nlohmann::json::array(), spurious = nlohmann::json::array();
    for (const auto r : ev.missed) missed.push_back(c.reference[r].id);
    for (const auto e : ev.spurious) spurious.push_back(c.estimate[e].id);
    if (!ev.missed.empty()) table << "  missed:   " << missed.dump() << "\n";
    if (!ev.spurious.empty()) table << "  spurious: " << spurious.dump() << "\n";
    const nlohmann::json why =
        diagnosis_lines(diagnose_entities(c.reference, c.estimate, ev, c.visibility), table);
    const nlohmann::json not_scored = not_scored_json(c, ev);
    const ClassBinScore all = unfiltered.within(bars.class_name, bars.max_range_m);
    if (!ev.ignored.empty()) not_scored_lines(c, not_scored, all, bars, o.iou_threshold, table);
    if (bars.any()) report_bars(ev, bars, table, report);
    report.json["entities"] = {{"entities_file", c.entities_file},
                               {"reference_file", c.reference_file},
                               {"max_match_distance_m", o.max_match_distance_m},
                               {"max_range_m", o.max_range_m},
                               {"iou_threshold", o.iou_threshold},
                               {"stuff_overlap", o.stuff_overlap},
                               {"classes", classes},
                               {"matches", matches_json(c, ev)},
                               {"missed", missed},
                               {"spurious", spurious},
                               {"diagnosis", why},
                               {"min_visible_pixels", c.min_visible_pixels},
                               {"min_visible_fraction", c.min_visible_fraction},
                               {"not_scored", not_scored},
                               {"unfiltered",
                                {{"class", bars.class_name},
                                 {"max_range_m", bars.max_range_m},
                                 {"reference", all.reference},
                                 {"matched", all.matched},
                                 {"recall", all.recall()},
                                 {"good_iou", all.good_iou},
                                 {"good_iou_fraction", all.good_iou_fraction()}}}};
    report.table += table.str();
}

void report_cars(const std::string& entities_file,
                 const std::vector<scene_schema::Entity>& entities, const std::vector<GtCar>& gt,
                 const CarMatchOptions& options, const GtCarOptions& gt_options,
                 const StereoCamera* fallback_camera, EvaluationReport& report,
                 const InstanceImage* image, const StereoCamera* camera) {
    const CarEvaluation ev = evaluate_cars(entities, gt, options, fallback_camera);
    const bool with_fallback = fallback_camera != nullptr;
    std::ostringstream table;
    table << "cars within " << fixed_text(options.max_range_m, 0)
          << " m (GT owed: >= " << options.min_gt_pixels
          << " GT disparity px of the car's own surface; occluder gap "
          << fixed_text(gt_options.occluder_gap_m, 2) << " m)\n";
    table << "  GT inst   pixels occluder  range_m  matched_entity  rule  inside  iou_2d  "
             "centre_dist_m\n";
    const nlohmann::json cars = car_rows(entities, gt, ev, options, table);
    table << "  recall    " << ev.gt_owed_matched << "/" << ev.gt_owed << " = "
          << fixed_text(100.0 * ev.recall(), 1) << " %\n";
    table << "  precision " << ev.entities_matched << "/" << ev.entities_in_range << " = "
          << fixed_text(100.0 * ev.precision(), 1) << " %   (scorable: " << ev.entities_matched
          << "/" << ev.entities_in_range - ev.entities_unscorable << " = "
          << fixed_text(100.0 * ev.precision_scorable(), 1) << " %; " << ev.entities_unscorable
          << " entities lie on GT cars without GT points)\n";
    if (with_fallback) {
        table << "  matched by the 2D fallback (GT cars with <= " << options.fallback_max_points
              << " GT points, IoU >= " << fixed_text(options.fallback_min_iou, 2)
              << "): " << ev.fallback_matched << " of " << ev.entities_matched << "\n";
    } else {
        table << "  2D fallback off\n";
    }
    table << "  mean centre distance " << fixed_text(ev.mean_centre_distance_m(), 2)
          << " m (entity centre to GT visible-point centroid, bird's-eye)\n";
    const nlohmann::json why =
        diagnosis_lines(diagnose_cars(entities, gt, ev, options, image, camera), table);
    report.json["cars"] = {
        {"entities_file", entities_file},
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
        {"gt_cars", cars},
        {"diagnosis", why}};
    report.table += table.str();
}

void report_ground_plane(const scene_schema::EntityDocument& doc, EvaluationReport& report) {
    if (!doc.extra.contains("ground_plane")) return;
    const double h = doc.extra["ground_plane"].value("camera_height_m", 0.0);
    report.json["ground_plane"] = doc.extra["ground_plane"];
    report.table += "ground plane: camera " + fixed_text(h, 3) + " m above it\n";
}

}  // namespace cloud_analysis
