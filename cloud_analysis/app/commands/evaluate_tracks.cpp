#include "evaluate_tracks.hpp"

#include <fstream>
#include <iostream>
#include <map>
#include <sstream>

#include "cloud_analysis/tracking/sequence.hpp"
#include "evaluate.hpp"
#include "output.hpp"

namespace cloud_analysis::app {

namespace fs = std::filesystem;

CLI::App* add_evaluate_tracks_command(CLI::App& app, EvaluateTracksArgs& a) {
    CLI::App* cmd = app.add_subcommand(
        "evaluate-tracks",
        "score a tracked drive: MOTA, ID switches, fragmentations, IDF1, velocity error "
        "(see docs/evaluation.md)");
    cmd->add_option("--tracks", a.tracks, "tracked drive: folder or sequence.json")->required();
    auto* truth = cmd->add_option("--truth", a.truth,
                                  "synthetic drive's truth: folder or sequence.json "
                                  "(scene-render sensors --frames writes DIR/truth)");
    auto* labels = cmd->add_option("--kitti-labels", a.kitti_labels,
                                   "KITTI tracking labels (label_02/<drive>.txt) as the truth");
    truth->excludes(labels);
    cmd->add_option("--fps", a.fps, "frame rate of the KITTI labels (their velocities), Hz")
        ->capture_default_str();
    cmd->add_option("--visibility", a.visibility,
                    "folder of scene-render sensors' visibility/<frame>.json");
    cmd->add_option("--min-visible-fraction", a.min_visible_fraction,
                    "truth less visible than this is not owed (needs --visibility)")
        ->capture_default_str();
    cmd->add_option("--match-distance", a.options.max_match_distance_m,
                    "bird's-eye centre distance of a match, m")
        ->capture_default_str();
    cmd->add_option("--eval-range", a.options.max_range_m, "truth farther than this is not owed, m")
        ->capture_default_str();
    cmd->add_flag("--events", a.events,
                  "after the table, one line per miss, false positive, ID switch and heading "
                  "flip, by class and frame");
    const std::string bg = "Bars (exit 3 when one is missed; off unless given)";
    cmd->add_option("--class", a.bars.class_name, "class the bars apply to")
        ->capture_default_str()
        ->group(bg);
    cmd->add_option("--min-mota", a.bars.min_mota, "lowest MOTA")->group(bg);
    cmd->add_option("--max-id-switches", a.bars.max_id_switches, "most ID switches")->group(bg);
    cmd->add_option("--min-idf1", a.bars.min_idf1, "lowest IDF1")->group(bg);
    cmd->add_option("--max-velocity-error", a.bars.max_median_moving_velocity_error_mps,
                    "largest median velocity error of moving objects, m/s")
        ->group(bg);
    cmd->add_option("--max-still-velocity-error", a.bars.max_median_still_velocity_error_mps,
                    "largest median velocity error of still objects (parked cars), m/s")
        ->group(bg);
    cmd->add_option("--max-heading-flips", a.bars.max_heading_flips, "most heading flips")
        ->group(bg);
    cmd->add_option("--max-size-spread", a.bars.max_parked_size_spread_m,
                    "largest size spread of a track on a still object, m")
        ->group(bg);
    return cmd;
}

namespace {

fs::path index_path_of(const fs::path& p) { return fs::is_directory(p) ? p / "sequence.json" : p; }

/// frame index -> hypotheses of the tracked drive.
std::map<std::int64_t, std::vector<TrackedObject>> read_tracks(const fs::path& tracks) {
    const auto path = index_path_of(tracks);
    const auto index = scene_schema::read_sequence_file(path);
    std::map<std::int64_t, std::vector<TrackedObject>> out;
    for (const auto& f : index.frames) {
        out[f.index] = hypotheses_of(scene_schema::read_file(scene_schema::frame_file(path, f)));
    }
    return out;
}

/// frame index -> truth of a synthetic drive, owed by visibility when asked.
std::map<std::int64_t, std::vector<TrackedObject>> read_truth(const EvaluateTracksArgs& a) {
    const auto path = index_path_of(a.truth);
    const auto index = scene_schema::read_sequence_file(path);
    std::map<std::int64_t, std::vector<TrackedObject>> out;
    for (const auto& f : index.frames) {
        const auto doc = scene_schema::read_file(scene_schema::frame_file(path, f));
        std::vector<bool> owed;
        if (!a.visibility.empty()) {
            const auto file = a.visibility / (fs::path(f.file).stem().string() + ".json");
            const auto seen = load_reference_visibility(file, doc.entities, EntityEvalOptions{});
            for (const auto& v : seen) {
                owed.push_back(!v || v->visible_fraction >= a.min_visible_fraction);
            }
        }
        out[f.index] = truth_of(doc, owed);
    }
    return out;
}

}  // namespace

int run_evaluate_tracks(const EvaluateTracksArgs& a) {
    if (a.truth.empty() == a.kitti_labels.empty()) {
        throw CLI::ValidationError("--truth", "give --truth or --kitti-labels");
    }
    if (a.min_visible_fraction > 0.0 && a.visibility.empty()) {
        throw CLI::ValidationError("--min-visible-fraction", "needs --visibility");
    }
    try {
        a.options.validate();
    } catch (const std::invalid_argument& e) {
        throw CLI::ValidationError("evaluate-tracks", e.what());
    }
    std::map<std::int64_t, std::vector<TrackedObject>> truth;
    if (!a.kitti_labels.empty()) {
        std::ifstream in(a.kitti_labels, std::ios::binary);
        if (!in) throw std::runtime_error("cannot read labels (" + a.kitti_labels.string() + ")");
        std::stringstream text;
        text << in.rdbuf();
        truth = parse_kitti_tracking_labels(text.str(), a.kitti_labels.string(), a.fps);
    } else {
        truth = read_truth(a);
    }
    auto hypotheses = read_tracks(a.tracks);
    std::vector<TrackedFrame> frames;
    for (auto& [index, objects] : truth) {
        TrackedFrame f;
        f.index = index;
        f.truth = std::move(objects);
        if (auto it = hypotheses.find(index); it != hypotheses.end()) f.hypotheses = it->second;
        frames.push_back(std::move(f));
    }
    const auto evaluation = evaluate_tracks(frames, a.options);
    std::cout << format_track_report(evaluation);
    if (a.events) {
        for (const auto& c : evaluation.classes) {
            for (const auto& e : c.events) std::cout << c.class_name << " " << describe(e) << "\n";
        }
    }
    const auto missed = check_track_bars(evaluation, a.bars);
    for (const auto& m : missed) std::cerr << kTool << ": bar missed: " << m << "\n";
    return missed.empty() ? 0 : kExitBarMissed;
}

}  // namespace cloud_analysis::app
