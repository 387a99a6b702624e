#include "batch.hpp"

#include <malloc.h>
#include <unistd.h>

#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <fstream>
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
    if (!std::filesystem::is_directory(a.kitti_root)) {
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
    options.frames = std::move(frames);
    options.out_dir = a.out_dir;
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
    return report;
}

}  // namespace

CLI::App* add_batch_command(CLI::App& app, BatchArgs& a) {
    CLI::App* cmd = app.add_subcommand(
        "batch",
        "analyse many KITTI-layout frames in one process (matcher, calibration and palette "
        "kept; decoding and writing overlap matching)");
    cmd->add_option("--kitti-root", a.kitti_root,
                    "KITTI folder: image_2/ image_3/ semantic_rgb/ calib/")
        ->required();
    auto* frames = cmd->add_option("--frames", a.frames, "frame ids, e.g. 000000_10 000001_10");
    auto* list = cmd->add_option("--list", a.list, "file of frame ids, one per line (# comments)");
    frames->excludes(list);
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

void resolve_batch(BatchArgs& a, const CLI::App& cmd) {
    if (!a.list.empty()) a.frames = read_frame_list(a.list);
    if (a.frames.empty()) throw CLI::RequiredError("--frames or --list (with frames)");
    for (const std::string& frame : a.frames) {
        if (const std::string problem = frame_id_problem(frame); !problem.empty()) {
            throw CLI::ValidationError("--frames", "frame id '" + frame + "' " + problem);
        }
    }
    try {
        a.shard = a.shard_text.empty() ? shard_from_slurm(std::getenv("SLURM_ARRAY_TASK_ID"),
                                                          std::getenv("SLURM_ARRAY_TASK_COUNT"))
                                       : parse_shard(a.shard_text);
    } catch (const std::invalid_argument& e) {
        throw CLI::ValidationError("--shard", e.what());
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
