#include "evaluate_command.hpp"

#include <cmath>
#include <cstdio>
#include <iostream>
#include <sstream>
#include <stdexcept>

#include <nlohmann/json.hpp>
#include <scene_schema/entities.hpp>

#include "cloud_analysis/calibration.hpp"
#include "cloud_analysis/disparity.hpp"
#include "cloud_analysis/evaluate.hpp"
#include "cloud_analysis/io.hpp"

namespace cloud_analysis::app {
namespace {

namespace fs = std::filesystem;

/// Input paths after applying the KITTI layout defaults.
struct ResolvedPaths {
    fs::path gt_disparity, instance, calib;
};

ResolvedPaths resolve(const EvaluateArgs& args) {
    ResolvedPaths p{args.gt_disparity, args.instance, args.calib};
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
        if (!fs::is_regular_file(f, ec)) {
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
    return sub;
}

void run_evaluate(const EvaluateArgs& args) {
    const ResolvedPaths paths = resolve(args);
    nlohmann::json out = nlohmann::json::object();
    if (!args.frame.empty()) out["frame"] = args.frame;
    std::ostringstream table;

    const DisparityMap gt_disparity = read_kitti_disparity(paths.gt_disparity);
    if (!args.disparity.empty()) {
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

    if (!args.entities.empty()) {
        const scene_schema::EntityDocument doc = scene_schema::read_file(args.entities);
        const Calibration calib = load_calibration(paths.calib);
        const std::vector<GtCar> gt =
            load_gt_cars(paths.instance, paths.gt_disparity, calib.camera);
        CarMatchOptions options;
        options.max_range_m = args.max_range_m;
        options.min_gt_pixels = static_cast<std::size_t>(args.min_gt_pixels);
        const CarEvaluation ev = evaluate_cars(doc.entities, gt, options, &calib.camera);

        nlohmann::json cars = nlohmann::json::array();
        table << "cars within " << fixed(options.max_range_m, 0)
              << " m (GT owed: >= " << options.min_gt_pixels << " GT disparity px)\n";
        table << "  GT inst   pixels  range_m  matched_entity  inside  centre_dist_m\n";
        for (std::size_t g = 0; g < gt.size(); ++g) {
            const GtCar& car = gt[g];
            const CarMatch* match = nullptr;
            for (const auto& m : ev.matches) {
                if (m.gt == g) match = &m;
            }
            const bool no_points = car.pixel_count == 0;
            const bool in_range = !no_points && car.range_m() <= options.max_range_m;
            const bool owed = in_range && car.pixel_count >= options.min_gt_pixels;
            nlohmann::json row = {
                {"instance", car.instance},
                {"pixels", car.pixel_count},
                {"range_m", no_points ? nlohmann::json() : nlohmann::json(car.range_m())},
                {"owed", owed},
                {"entity", match ? doc.entities[match->entity].id : ""},
                {"inside_fraction", match ? match->inside_fraction : 0.0},
                {"centre_distance_m", match ? match->centre_distance_m : 0.0}};
            cars.push_back(row);
            if (!in_range) continue;
            char line[160];
            std::snprintf(line, sizeof line, "  %7d %8zu %8.1f  %-14s %6s %14s%s\n", car.instance,
                          car.pixel_count, car.range_m(),
                          match ? doc.entities[match->entity].id.c_str() : "-",
                          match ? fixed(match->inside_fraction, 2).c_str() : "-",
                          match ? fixed(match->centre_distance_m, 2).c_str() : "-",
                          owed ? "" : "  (not owed)");
            table << line;
        }
        table << "  recall    " << ev.gt_owed_matched << "/" << ev.gt_owed << " = "
              << fixed(100.0 * ev.recall(), 1) << " %\n";
        table << "  precision " << ev.entities_matched << "/" << ev.entities_in_range << " = "
              << fixed(100.0 * ev.precision(), 1) << " %   (scorable: " << ev.entities_matched
              << "/" << ev.entities_in_range - ev.entities_unscorable << " = "
              << fixed(100.0 * ev.precision_scorable(), 1) << " %; " << ev.entities_unscorable
              << " entities lie on GT cars without GT disparity)\n";
        table << "  mean centre distance " << fixed(ev.mean_centre_distance_m(), 2)
              << " m (entity centre to GT visible-point centroid, bird's-eye)\n";
        out["cars"] = {{"entities_file", args.entities.string()},
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
        scene_schema::write_file_atomic(args.json, json_text);
    }
}

}  // namespace cloud_analysis::app
