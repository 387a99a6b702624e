#include "batch.hpp"

#include <malloc.h>
#include <unistd.h>

#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <map>
#include <stdexcept>

#include <nlohmann/json.hpp>

#include "cloud_analysis/pipeline/batch.hpp"
#include "cloud_analysis/pipeline/frame_list.hpp"
#include "cloud_analysis/pipeline/resume.hpp"
#include "cloud_analysis/support/progress.hpp"
#include "output.hpp"
#include "stereoscene/support/error_line.hpp"
#include "stereoscene/support/file_read.hpp"
#include "stereoscene/support/output_transaction.hpp"

namespace cloud_analysis::app {
namespace {

std::vector<std::string> read_frame_list(const std::filesystem::path& path) {
    std::string text;
    try {
        text = stereoscene::support::read_text_input(path);
    } catch (const stereoscene::support::FileError& e) {
        throw std::runtime_error("cannot read frame list: " + e.reason() + " (" + path.string() +
                                 ", --list)");
    }
    return parse_frame_list(text, path.string() + ", --list");
}

/// Checks the input folder and the report's folder, then creates --out-dir when it is missing
/// (with its parents), last, so that a refused run leaves nothing behind.
void check_batch_folders(const BatchArgs& a) {
    if (a.drive.empty() && !std::filesystem::is_directory(a.kitti_root)) {
        throw std::runtime_error("cannot read frames: no such folder (" + a.kitti_root.string() +
                                 ", --kitti-root)");
    }
    if (!a.report.empty() && a.report != "-") {
        try {
            stereoscene::support::check_output_path(a.report);
        } catch (const stereoscene::support::FileError& e) {
            throw std::runtime_error("cannot write output: " + e.reason() + " (" +
                                     a.report.string() + ", --report)");
        }
    }
    std::error_code ec;
    if (std::filesystem::is_directory(a.out_dir, ec)) return;
    if (std::filesystem::exists(a.out_dir, ec)) {
        throw std::runtime_error("cannot write output: not a folder (" + a.out_dir.string() +
                                 ", --out-dir)");
    }
    std::filesystem::create_directories(a.out_dir, ec);
    if (ec) {
        throw std::runtime_error("cannot write output: cannot create the folder: " + ec.message() +
                                 " (" + a.out_dir.string() + ", --out-dir)");
    }
}

/// Frames whose analysis warned (per_frame records with "warnings").
std::vector<std::pair<std::string, std::string>> warned_frames(const nlohmann::json& per_frame) {
    std::vector<std::pair<std::string, std::string>> out;
    for (const auto& record : per_frame) {
        if (record.contains("warnings") && !record["warnings"].empty()) {
            out.emplace_back(record["frame"].get<std::string>(),
                             record["warnings"][0].get<std::string>());
        }
    }
    return out;
}

/// The frames of the share still to do: all of them, or with --resume those whose outputs are
/// not all complete and valid (the share's stale temporary files are removed first).
std::vector<std::string> frames_to_do(const BatchArgs& a, std::size_t& skipped) {
    skipped = 0;
    if (!a.resume) return a.frames;
    const FrameOutputs outputs{a.cloud_formats, a.disparity_kitti};
    remove_stale_temporaries(a.out_dir, a.frames, outputs);
    std::vector<std::string> todo;
    for (const auto& frame : a.frames) {
        if (frame_outputs_problem(a.out_dir, frame, outputs).empty()) {
            ++skipped;
        } else {
            todo.push_back(frame);
        }
    }
    return todo;
}

double unix_seconds() {
    return std::chrono::duration<double>(std::chrono::system_clock::now().time_since_epoch())
        .count();
}

/// The library's settings of a batch from the flags, for `frames`.
cloud_analysis::BatchOptions batch_options(const BatchArgs& a, std::vector<std::string> frames) {
    cloud_analysis::BatchOptions options;
    options.kitti_root = a.kitti_root;
    options.kitti_instances = a.instances;
    options.odometry = a.odometry;
    options.odometry_options.estimate_disparity_offset = !a.fixed_disparity_offset;
    options.frames = std::move(frames);
    if (!a.drive.empty()) {
        // The share's frames, in the drive's order.
        std::map<std::string, const cloud_analysis::DriveFrame*> by_id;
        for (const auto& f : a.drive) by_id[f.id] = &f;
        for (const auto& id : options.frames) options.drive.push_back(*by_id.at(id));
    }
    if (a.track) {
        options.track = a.track_options;
        // Each frame is written once tracked: no frames are held to smooth.
        options.track->smooth = false;
        // The drive's folder, or the folder of the list of pairs (absolute first: a bare file
        // name has no parent of its own).
        const std::filesystem::path source =
            !a.drive_dir.empty() ? std::filesystem::absolute(a.drive_dir)
            : !a.pairs.empty()   ? std::filesystem::absolute(a.pairs).parent_path()
                                 : std::filesystem::absolute(a.kitti_root);
        options.sequence_id = source.lexically_normal().filename().string();
        if (options.sequence_id.empty()) options.sequence_id = "drive";
    }
    options.out_dir = a.out_dir;
    if (a.shard.count > 1) {
        options.lock_name = ".batch-" + std::to_string(a.shard.index) + "-of-" +
                            std::to_string(a.shard.count) + ".lock";
    }
    options.cloud_formats = a.cloud_formats;
    options.cloud_drop_classes = a.settings.drop_classes;
    options.disparity_kitti = a.disparity_kitti;
    options.fsync_clouds = a.settings.fsync_clouds;
    options.evaluate = a.evaluate;
    options.extract = extract_options(a.settings);
    options.run = run_settings(a.settings);
    return options;
}

/// The --report document of a finished batch.
nlohmann::json report_json(const BatchArgs& a, const cloud_analysis::BatchReport& r,
                           std::size_t skipped, double started_at) {
    nlohmann::json report = {{"shard", {{"index", a.shard.index}, {"count", a.shard.count}}},
                             {"list_frames", a.list_frames},
                             {"frames", a.frames.size()},
                             {"done", r.frames - r.failed},
                             {"skipped", skipped},
                             {"failed", r.failed},
                             {"failures", r.failures},
                             {"started_at", started_at},
                             {"ended_at", unix_seconds()},
                             {"seconds", r.seconds},
                             {"fps", r.fps},
                             {"cpu_seconds", r.cpu_seconds},
                             {"peak_rss_mb", cloud_analysis::peak_rss_mb()},
                             {"cpu_ms_per_frame", r.cpu_ms_per_frame},
                             {"cores", r.cores},
                             {"cores_busy", r.cores_busy},
                             {"preset", a.settings.preset},
                             {"frames_with_warnings", warned_frames(r.per_frame).size()},
                             {"per_frame", r.per_frame}};
    if (r.evaluation.frames > 0) report["evaluation"] = r.evaluation.to_json();
    if (r.disparity_offset_px) report["disparity_offset_px"] = *r.disparity_offset_px;
    return report;
}

/// The tracker's flags of `batch --track`.
void add_tracking_flags(CLI::App& sub, BatchArgs& a) {
    CLI::App* cmd = &sub;
    cmd->add_option("--fps", a.track_options.fps,
                    "--track: frame rate when frames carry no timestamps, Hz")
        ->capture_default_str();
    cmd->add_option("--min-hits", a.track_options.tracker.min_hits,
                    "--track: hits before a track is reported")
        ->capture_default_str();
    cmd->add_option("--max-misses", a.track_options.tracker.max_misses,
                    "--track: frames without a hit before a confirmed track dies")
        ->capture_default_str();
    cmd->add_option("--coast", a.track_options.tracker.coast_frames,
                    "--track: frames a confirmed track missed by the detector is still "
                    "reported, at its prediction")
        ->capture_default_str();
    cmd->add_option("--coast-min-hits", a.track_options.tracker.coast_min_hits,
                    "--track: only a track hit at least this often coasts")
        ->capture_default_str();
    cmd->add_option("--support", a.track_options.tracker.support_frames,
                    "--track: frames a still track missed by the detector is still reported "
                    "while a piece of something lies on its footprint (0 = off; see `track`)")
        ->capture_default_str();
    cmd->add_option("--gate-chi2", a.track_options.tracker.gate_chi2,
                    "--track: statistical gate, squared Mahalanobis distance from a track's "
                    "prediction (0 = off; see `track`)")
        ->capture_default_str();
}

}  // namespace

CLI::App* add_batch_command(CLI::App& app, BatchArgs& a) {
    CLI::App* cmd = app.add_subcommand(
        "batch",
        "analyse many KITTI-layout frames in one process (matcher, calibration and palette "
        "kept; decoding and writing overlap matching)");
    auto* root = cmd->add_option("--kitti-root", a.kitti_root,
                                 "KITTI folder: image_2/ image_3/ semantic_rgb/ calib/ (with "
                                 "--frames or --list)");
    auto* drive = cmd->add_option("--drive", a.drive_dir,
                                  "KITTI raw drive folder: image_02/data/*.png, image_03/data/, "
                                  "image_02/timestamps.txt; calib_cam_to_cam.txt beside or above");
    auto* pairs =
        cmd->add_option("--pairs", a.pairs,
                        "file of frames, one a line: LEFT RIGHT [SEMANTIC [INSTANCE]] (paths "
                        "relative to the file; needs --calib)");
    root->excludes(drive)->excludes(pairs);
    drive->excludes(pairs);
    auto* frames = cmd->add_option("--frames", a.frames, "frame ids, e.g. 000000_10 000001_10");
    auto* list = cmd->add_option("--list", a.list, "file of frame ids, one per line (# comments)");
    frames->excludes(list);
    for (auto* f : {frames, list}) f->excludes(drive)->excludes(pairs);
    cmd->add_option("--calib,-c", a.calib, "calibration of --drive (default: found) or --pairs");
    cmd->add_option("--semantic-dir", a.semantic_dir,
                    "--drive: semantic images, one per left image of the same name");
    cmd->add_option("--instance-dir", a.instance_dir,
                    "--drive: instance images, one per left image of the same name (see "
                    "--instance-encoding)");
    cmd->add_flag("--instances", a.instances,
                  "--kitti-root: also read instance/<frame>.png: each object taken whole");
    cmd->add_flag("--track", a.track,
                  "track the frames in order: entity files with track_id and velocity, and "
                  "<out-dir>/sequence.json (see `track`)");
    cmd->add_flag("--odometry", a.odometry,
                  "estimate where the camera went from frame to frame (stereo visual odometry): "
                  "<out-dir>/poses.txt (KITTI odometry format) and each entity file's frame.pose");
    cmd->add_flag("--no-disparity-offset", a.fixed_disparity_offset,
                  "--odometry: take the disparities as they are (no rig disparity offset "
                  "estimated from the motion)");
    add_tracking_flags(*cmd, a);
    cmd->add_option("--out-dir", a.out_dir, "output folder: <frame>.json per frame")->required();
    cmd->add_option("--clouds", a.cloud_formats, "also write <frame>.<fmt> clouds: xyz pcd ply")
        ->check(CLI::IsMember({"xyz", "pcd", "ply"}));
    cmd->add_flag("--disparity-kitti", a.disparity_kitti,
                  "also write <frame>_disparity.png (KITTI 16-bit)");
    cmd->add_option("--report", a.report,
                    "JSON report: counts, failures, fps, CPU time, per-frame ms and resident "
                    "memory ('-' = stdout); merge shards' reports with `report`");
    cmd->add_option("--shard", a.shard_text,
                    "I/N: do frames I, I+N, I+2N, ... of the list (default: "
                    "SLURM_ARRAY_TASK_ID/SLURM_ARRAY_TASK_COUNT when set, else all)");
    cmd->add_flag("--resume", a.resume,
                  "skip frames whose outputs are all there, complete and valid");
    cmd->add_flag("--evaluate", a.evaluate,
                  "score each frame's disparity against <kitti-root>/disp_occ_0/<frame>.png "
                  "when present (D1-all, EPE, density in the report)");
    cmd->add_flag("--quiet,-q", a.quiet, "no progress and no summary line (errors only)");
    cmd->add_option("--progress-every", a.progress_every_s,
                    "seconds between progress lines when stderr is not a terminal")
        ->capture_default_str()
        ->check(CLI::Range(0.1, 86400.0));
    add_settings_flags(*cmd, a.settings);
    cmd->footer(
        "A frame that fails is named on stderr and skipped; exit 1 if any frame failed. Every "
        "file of a frame is written atomically and the entity file last, so a killed run "
        "leaves each frame whole or without its entity file (redone by --resume).");
    return cmd;
}

namespace {

/// The frames of --drive or --pairs (read now: the share and --resume need their ids).
void read_drive(BatchArgs& a) {
    if (!a.drive_dir.empty()) {
        a.drive =
            cloud_analysis::kitti_raw_drive(a.drive_dir, a.calib, a.semantic_dir, a.instance_dir);
    } else {
        std::string text;
        try {
            text = stereoscene::support::read_text_input(a.pairs);
        } catch (const stereoscene::support::FileError& e) {
            throw std::runtime_error("cannot read frame list: " + e.reason() + " (" +
                                     a.pairs.string() + ", --pairs)");
        }
        a.drive = cloud_analysis::pair_list(text, a.pairs.parent_path(), a.calib,
                                            a.pairs.string() + ", --pairs");
    }
    a.frames.clear();
    for (const auto& f : a.drive) a.frames.push_back(f.id);
}

/// The flags that only make sense with one input kind, and --track's limits.
void check_batch_flags(const BatchArgs& a) {
    if (a.kitti_root.empty() && a.drive_dir.empty() && a.pairs.empty())
        throw CLI::RequiredError("--kitti-root, --drive or --pairs");
    if (!a.pairs.empty() && a.calib.empty())
        throw CLI::ValidationError("--calib", "is required with --pairs");
    if (!a.kitti_root.empty() && !a.calib.empty())
        throw CLI::ValidationError("--calib",
                                   "only with --drive or --pairs (a KITTI root has calib/)");
    if (!a.semantic_dir.empty() && a.drive_dir.empty())
        throw CLI::ValidationError("--semantic-dir", "only with --drive");
    if (!a.instance_dir.empty() && a.drive_dir.empty())
        throw CLI::ValidationError("--instance-dir", "only with --drive");
    if (a.instances && a.kitti_root.empty())
        throw CLI::ValidationError("--instances", "only with --kitti-root (its instance/)");
    if (a.evaluate && a.kitti_root.empty())
        throw CLI::ValidationError("--evaluate", "needs --kitti-root (its disp_occ_0/)");
    if (a.track && a.resume)
        throw CLI::ValidationError("--track",
                                   "cannot resume: the tracker needs every frame in order");
    if (a.track && a.shard.count > 1)
        throw CLI::ValidationError("--track", "cannot track a share of the frames (--shard)");
    if (a.odometry && a.resume)
        throw CLI::ValidationError("--odometry",
                                   "cannot resume: the odometry needs every frame in order");
    if (a.odometry && a.shard.count > 1)
        throw CLI::ValidationError("--odometry", "cannot chain a share of the frames (--shard)");
    if (a.fixed_disparity_offset && !a.odometry)
        throw CLI::ValidationError("--no-disparity-offset", "needs --odometry");
    if (a.odometry && a.settings.options.raw)
        throw CLI::ValidationError("--odometry", "needs rectified frames (not --raw)");
    try {
        a.track_options.validate();
    } catch (const std::invalid_argument& e) {
        throw CLI::ValidationError("--track", e.what());
    }
}

}  // namespace

void resolve_batch(BatchArgs& a, const CLI::App& cmd) {
    try {
        a.shard = a.shard_text.empty() ? shard_from_slurm(std::getenv("SLURM_ARRAY_TASK_ID"),
                                                          std::getenv("SLURM_ARRAY_TASK_COUNT"))
                                       : parse_shard(a.shard_text);
    } catch (const std::invalid_argument& e) {
        throw CLI::ValidationError("--shard", e.what());
    }
    check_batch_flags(a);  // every usage error before any file is read
    if (!a.list.empty()) a.frames = read_frame_list(a.list);
    if (!a.drive_dir.empty() || !a.pairs.empty()) read_drive(a);
    if (a.frames.empty()) throw CLI::RequiredError("--frames or --list (with frames)");
    for (const std::string& frame : a.frames) {
        if (const std::string problem = frame_id_problem(frame); !problem.empty()) {
            throw CLI::ValidationError("--frames", "frame id '" + frame + "' " + problem);
        }
    }
    a.list_frames = a.frames.size();
    a.frames = shard_frames(a.frames, a.shard);
    resolve_settings(a.settings, cmd);
}

int run_batch(const BatchArgs& a) {
    check_batch_folders(a);
    const double started_at = unix_seconds();
    std::size_t skipped = 0;
    const std::vector<std::string> frames = frames_to_do(a, skipped);
    const std::string label = std::string(kTool) + ": batch" +
                              (a.shard.count > 1 ? " " + std::to_string(a.shard.index) + "/" +
                                                       std::to_string(a.shard.count)
                                                 : std::string());
    if (!a.quiet && (a.shard.count > 1 || a.resume)) {
        std::fprintf(stderr, "%s: %zu of %zu frames in this share, %zu already done, %zu to do\n",
                     label.c_str(), a.frames.size(), a.list_frames, skipped, frames.size());
    }
    // Three threads allocate frame-sized buffers: with glibc's default of up to 8 arenas per
    // core each thread's frees stay in its own arena and the resident set creeps up (kitti15,
    // fast preset: peak 227 MB, still rising after 60 frames); two arenas keep it flat (196 MB).
    mallopt(M_ARENA_MAX, 2);
    const cloud_analysis::BatchOptions options = batch_options(a, frames);
    ProgressMeter::Options progress_options;
    progress_options.terminal = isatty(STDERR_FILENO) != 0;
    progress_options.line_interval_s = a.progress_every_s;
    ProgressMeter progress(label, frames.size(), progress_options);
    bool bar_open = false;  // a bar is drawn without its newline: an error line starts one
    cloud_analysis::BatchObserver observer;
    observer.failed = [&bar_open](const std::string& frame, const std::string& what) {
        std::fprintf(stderr, "%s%s\n", bar_open ? "\n" : "",
                     stereoscene::support::error_line_of(kTool, "frame " + frame, what).c_str());
        bar_open = false;
    };
    observer.not_scored = [&bar_open](const std::string& frame, const std::string& what) {
        std::fprintf(stderr, "%s%s: warning: frame %s: not scored: %s\n", bar_open ? "\n" : "",
                     kTool, frame.c_str(), what.c_str());
        bar_open = false;
    };
    observer.warning = [](const std::string& warning) {
        std::fprintf(stderr, "%s: warning: %s\n", kTool, warning.c_str());
    };
    observer.progress = [&](std::size_t done, std::size_t, std::size_t failed, double seconds) {
        if (a.quiet) return;
        const std::string text = progress.update(done, failed, seconds);
        if (text.empty()) return;
        std::fputs(text.c_str(), stderr);
        bar_open = text.back() != '\n';
    };
    const cloud_analysis::BatchReport r = cloud_analysis::run_batch(options, observer);
    if (!a.quiet) {
        std::fprintf(stderr,
                     "%s%s: %zu frames in %.2f s (%.2f fps), %zu failed, peak RSS %.0f MB, "
                     "%.0f ms CPU per frame, cores %.0f %% busy\n",
                     bar_open ? "\n" : "", label.c_str(), r.frames, r.seconds, r.fps, r.failed,
                     cloud_analysis::peak_rss_mb(), r.cpu_ms_per_frame, 100.0 * r.cores_busy);
    }
    if (!a.quiet && r.tracking) {
        std::fprintf(
            stderr,
            "%s: tracked %zu frames, %zu tracks, %zu restarts, tracker %.3f ms per frame -> %s\n",
            label.c_str(), r.tracking->tracked, r.tracking->tracks, r.tracking->restarts,
            r.tracking->tracked ? r.tracking->track_ms / r.tracking->tracked : 0.0,
            (a.out_dir / "sequence.json").string().c_str());
    }
    if (!a.quiet && r.disparity_offset_px) {
        std::fprintf(stderr, "%s: odometry: the rig's disparity offset %+.2f px -> %s\n",
                     label.c_str(), *r.disparity_offset_px,
                     (a.out_dir / "poses.txt").string().c_str());
    }
    const auto warned = warned_frames(r.per_frame);
    if (!a.quiet && !warned.empty()) {
        std::fprintf(
            stderr, "%s: warning: %zu of %zu frames warned, first frame %s: %s%s\n", label.c_str(),
            warned.size(), r.frames, warned[0].first.c_str(), warned[0].second.c_str(),
            a.report.empty() ? " (every warning in --report)" : " (every warning in the report)");
    }
    if (!a.report.empty()) {
        write_output(
            {a.report.string(), report_json(a, r, skipped, started_at).dump(1) + "\n", "--report"});
    }
    return r.failed == 0 ? 0 : 1;
}

}  // namespace cloud_analysis::app
