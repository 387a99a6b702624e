#include "track.hpp"

#include <chrono>
#include <cstdio>
#include <iostream>
#include <random>

#include "output.hpp"

namespace cloud_analysis::app {

namespace tr = cloud_analysis::tracking;

CLI::App* add_track_command(CLI::App& app, TrackArgs& a) {
    CLI::App* cmd = app.add_subcommand(
        "track",
        "track a drive's entity files in order: track_id, velocity, smoothed boxes, "
        "sequence.json (see docs/cli.md)");
    cmd->add_option("input", a.input,
                    "folder of entity files (a batch's --out-dir; name order) or a sequence index");
    cmd->add_option("--out-dir", a.out_dir,
                    "output folder: one entity file per frame + sequence.json");
    auto& o = a.options;
    cmd->add_option("--fps", o.fps, "frame rate when the files carry no timestamps, Hz")
        ->capture_default_str();
    cmd->add_option("--min-hits", o.tracker.min_hits, "hits before a track is reported")
        ->capture_default_str();
    cmd->add_option("--max-misses", o.tracker.max_misses,
                    "frames without a hit before a confirmed track dies")
        ->capture_default_str();
    cmd->add_option("--settle-hits", o.tracker.size_settle_hits,
                    "hits after confirmation during which a track's size may still change")
        ->capture_default_str();
    cmd->add_flag("!--no-first-frames", o.tracker.confirm_first_frames,
                  "do not report tracks born in the first frames before their min-hits");
    cmd->add_option("--coast", o.tracker.coast_frames,
                    "frames a confirmed track missed by the detector is still reported, at its "
                    "prediction")
        ->capture_default_str();
    cmd->add_option("--coast-min-hits", o.tracker.coast_min_hits,
                    "only a track hit at least this often coasts")
        ->capture_default_str();
    cmd->add_option("--support", o.tracker.support_frames,
                    "frames a still track missed by the detector is still reported while a "
                    "piece of something lies on its footprint (0 = off)")
        ->capture_default_str();
    cmd->add_option("--lag", o.lag_frames,
                    "frames held before writing, so a track whose motion shows it was reported "
                    "facing backwards is turned round in them too")
        ->capture_default_str();
    cmd->add_flag("!--no-smooth", o.smooth,
                  "write each frame with the filter's state then, not smoothed over the frames "
                  "held after it (--lag)");
    cmd->add_flag("!--no-hindsight", o.hindsight,
                  "do not place, in the frames held (--lag), the tracks still in the newest "
                  "frame where those frames' cameras see their place (docs/cli.md)");
    cmd->add_option("--max-gap", o.tracker.max_gap_s,
                    "a longer gap between frames restarts the tracker, s")
        ->capture_default_str();
    cmd->add_option("--car-gate", o.tracker.gate_m["car"],
                    "how far a car may be from its track's prediction, m")
        ->capture_default_str();
    cmd->add_option("--gate-chi2", o.tracker.gate_chi2,
                    "statistical gate: squared Mahalanobis distance from a track's prediction "
                    "(9.21 keeps 99 % of true matches; 0 = off)")
        ->capture_default_str();
    cmd->add_flag("--quiet", a.quiet, "no summary line on stderr");
    cmd->add_option("--bench-objects", a.bench_objects,
                    "benchmark: time the tracker on N moving objects per frame (no files)");
    cmd->add_option("--bench-frames", a.bench_frames, "benchmark: frames")->capture_default_str();
    return cmd;
}

namespace {

/// Times the tracker on `objects` cars driving in a grid within 53 m (at most 7 rows 8 m
/// apart, as many columns 6 m apart as that needs), each measured with noise.
int run_bench(const TrackArgs& a) {
    if (a.bench_objects < 1 || a.bench_frames < 1) {
        throw CLI::ValidationError("--bench-objects", "must be >= 1 (and --bench-frames too)");
    }
    std::mt19937 rng(1);
    std::normal_distribution<double> noise(0.0, 0.2);
    tr::Tracker tracker(a.options.tracker);
    double total_ms = 0.0, worst_ms = 0.0;
    const int columns = std::max(10, (a.bench_objects + 6) / 7);
    int lost_frames = 0;
    for (int f = 0; f < a.bench_frames; ++f) {
        scene_schema::EntityDocument doc;
        doc.frame.id = std::to_string(f);
        const double t = f / a.options.fps;
        for (int i = 0; i < a.bench_objects; ++i) {
            scene_schema::Entity e;
            e.id = "car-" + std::to_string(i);
            e.class_name = "car";
            e.class_id = 26;
            e.x = -3.0 * columns + 6.0 * (i % columns) + (i % 3 - 1) * 2.0 * t + noise(rng);
            e.z = 5.0 + 8.0 * (i / columns) + noise(rng);
            e.y = 0.9;
            e.W = 1.8;
            e.H = 1.5;
            e.L = 4.2;
            doc.entities.push_back(e);
        }
        const auto start = std::chrono::steady_clock::now();
        const auto out = tracker.update(doc, t);
        const double ms =
            std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start)
                .count();
        total_ms += ms;
        worst_ms = std::max(worst_ms, ms);
        // A coasted track is an object the tracker lost in this frame.
        lost_frames += out.entities.size() != doc.entities.size() ? 1 : 0;
    }
    std::printf("tracking %d objects: %.3f ms per frame (mean of %d frames), worst %.3f ms\n",
                a.bench_objects, total_ms / a.bench_frames, a.bench_frames, worst_ms);
    if (lost_frames > 0) {
        std::fprintf(stderr,
                     "cloud-analysis: error: the tracker lost an object in %d of %d frames\n",
                     lost_frames, a.bench_frames);
        return 1;
    }
    return 0;
}

}  // namespace

int run_track(const TrackArgs& a) {
    try {
        a.options.validate();
    } catch (const std::invalid_argument& e) {
        throw CLI::ValidationError("track", e.what());
    }
    if (a.bench_objects != 0) return run_bench(a);
    if (a.input.empty())
        throw CLI::ValidationError("input", "a folder or sequence index is required");
    if (a.out_dir.empty()) throw CLI::ValidationError("--out-dir", "is required");
    const auto index = tr::read_frames(a.input);
    const auto index_path =
        std::filesystem::is_directory(a.input) ? a.input / "sequence.json" : a.input;
    std::error_code ec;
    std::filesystem::create_directories(a.out_dir, ec);
    if (ec) {
        throw std::runtime_error("cannot create the output folder: " + ec.message() + " (" +
                                 a.out_dir.string() + ")");
    }
    const auto report = tr::track_files(
        index, index_path, a.out_dir, a.options,
        [](const std::string& warning) { std::cerr << kTool << ": warning: " << warning << "\n"; });
    if (!a.quiet) {
        std::fprintf(stderr,
                     "track: %zu of %zu frames, %zu tracks, %zu restarts, tracker %.3f ms per "
                     "frame -> %s\n",
                     report.tracked, report.frames, report.tracks, report.restarts,
                     report.tracked ? report.track_ms / report.tracked : 0.0,
                     (a.out_dir / "sequence.json").string().c_str());
    }
    return report.skipped == 0 ? 0 : 1;
}

}  // namespace cloud_analysis::app
