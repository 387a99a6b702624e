#include "perf_commands.hpp"

#include <malloc.h>
#include <sys/resource.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <ctime>
#include <exception>
#include <fstream>
#include <future>
#include <map>
#include <optional>
#include <thread>

#include <nlohmann/json.hpp>
#include <scene_schema/entities.hpp>

#include "cloud_analysis/cloud/cloud_io.hpp"
#include "cloud_analysis/pipeline/batch_report.hpp"
#include "cloud_analysis/pipeline/resume.hpp"
#include "cloud_analysis/stereo/disparity.hpp"
#include "cloud_analysis/support/progress.hpp"

namespace cloud_analysis::app {
namespace {

using Clock = std::chrono::steady_clock;

double ms_between(Clock::time_point a, Clock::time_point b) {
    return std::chrono::duration<double, std::milli>(b - a).count();
}

/// Peak resident set of this process so far, MB (getrusage's ru_maxrss is in KiB on Linux).
double peak_rss_mb() {
    rusage usage{};
    getrusage(RUSAGE_SELF, &usage);
    return static_cast<double>(usage.ru_maxrss) / 1024.0;
}

/// CPU time of this process so far (all threads, user + system), seconds.
double cpu_seconds() {
    rusage usage{};
    getrusage(RUSAGE_SELF, &usage);
    const auto seconds = [](const timeval& t) {
        return static_cast<double>(t.tv_sec) + static_cast<double>(t.tv_usec) / 1e6;
    };
    return seconds(usage.ru_utime) + seconds(usage.ru_stime);
}

/// Current resident set, MB (VmRSS of /proc/self/status; 0 when unavailable).
double current_rss_mb() {
    std::ifstream status("/proc/self/status");
    std::string key;
    while (status >> key) {
        if (key == "VmRSS:") {
            double kib = 0.0;
            status >> kib;
            return kib / 1024.0;
        }
        status.ignore(4096, '\n');
    }
    return 0.0;
}

double median(std::vector<double> v) {
    if (v.empty()) return 0.0;
    std::sort(v.begin(), v.end());
    const std::size_t n = v.size();
    return n % 2 == 1 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
}

/// One frame read from disk, or why it could not be.
struct LoadedFrame {
    std::string frame;
    std::optional<LoadedInputs> inputs;
    std::string error;
    double ms = 0.0;
};

/// One analysed frame handed to the finishing thread: entity extraction, formatting, writing.
struct FinishJob {
    LoadedInputs in;
    AnalyseResult result;
    const AnalyseArgs* settings = nullptr;
    const ExtractOptions* extract = nullptr;
    std::filesystem::path stem;  ///< out-dir/<frame>
    bool disparity_kitti = false;
    std::vector<std::string> cloud_formats;
    std::filesystem::path gt_disparity;  ///< scored against when set (--evaluate)
};

/// What finishing a frame gave: an error text ("" when none) and its milliseconds.
struct Finished {
    std::string error;
    double ms = 0.0;
    std::optional<DisparityScore> score;  ///< with ground truth
    std::string evaluation_error;         ///< why the ground truth could not be used
};

/// Extracts the entities, formats every output and writes them, all or nothing. The entity
/// file goes last: it marks the frame complete for --resume (a writer killed before it leaves
/// a frame that is redone).
Finished finish_frame(FinishJob job) {
    const auto start = Clock::now();
    std::vector<std::filesystem::path> written;
    Finished done;
    try {
        std::vector<PendingOutput> outputs;
        if (job.disparity_kitti) {
            outputs.push_back({job.stem.string() + "_disparity.png",
                               encode_kitti_disparity_png(job.result.disparity), ""});
        }
        for (const auto& fmt : job.cloud_formats) {
            const std::filesystem::path path = job.stem.string() + "." + fmt;
            outputs.push_back(
                {path.string(),
                 format_cloud(job.result.cloud, job.in.palette, cloud_format_from_path(path)), "",
                 cloud_sync(*job.settings)});
        }
        outputs.push_back({job.stem.string() + ".json",
                           entity_json(job.in, job.result, *job.settings, *job.extract), ""});
        for (const auto& out : outputs) {
            write_output(out);
            written.emplace_back(out.path);
        }
    } catch (const std::exception& e) {
        std::error_code ignored;
        for (const auto& path : written) std::filesystem::remove(path, ignored);
        done.error = e.what();
    }
    if (done.error.empty() && !job.gt_disparity.empty()) {
        try {
            done.score =
                score_disparity(job.result.disparity, read_kitti_disparity(job.gt_disparity));
        } catch (const std::exception& e) {
            done.evaluation_error = e.what();
        }
    }
    done.ms = ms_between(start, Clock::now());
    return done;
}

std::vector<std::string> read_frame_list(const std::filesystem::path& path) {
    std::ifstream in(path);
    if (!in)
        throw std::runtime_error("cannot read frame list: no such file (" + path.string() +
                                 ", --list)");
    std::vector<std::string> frames;
    std::string line;
    while (std::getline(in, line)) {
        const auto first = line.find_first_not_of(" \t\r");
        if (first == std::string::npos || line[first] == '#') continue;
        const auto last = line.find_last_not_of(" \t\r");
        frames.push_back(line.substr(first, last - first + 1));
    }
    return frames;
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

namespace {

void check_batch_folders(const BatchArgs& a) {
    if (!std::filesystem::is_directory(a.out_dir)) {
        throw std::runtime_error("cannot write output: no such folder (" + a.out_dir.string() +
                                 ", --out-dir)");
    }
    if (!a.report.empty() && a.report != "-") {
        const std::filesystem::path folder = a.report.parent_path();
        if (!folder.empty() && !std::filesystem::is_directory(folder)) {
            throw std::runtime_error("cannot write output: no such folder (" + folder.string() +
                                     ", --report)");
        }
    }
    if (!std::filesystem::is_directory(a.kitti_root)) {
        throw std::runtime_error("cannot read frames: no such folder (" + a.kitti_root.string() +
                                 ", --kitti-root)");
    }
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

}  // namespace

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
    const ExtractOptions extract = extract_options(a.settings);
    const Palette palette = [&] {
        try {
            return load_palette(a.settings.options.palette);
        } catch (const std::exception& e) {
            throw std::runtime_error(std::string("cannot read palette: ") + e.what());
        }
    }();
    // Without clouds the entities are extracted from points reprojected by class directly.
    const AnalyseOptions options = options_for_outputs(a.settings, extract, palette,
                                                       /*clouds=*/!a.cloud_formats.empty());
    DisparityMatcher matcher(options.disparity);
    std::map<std::filesystem::path, Calibration> calibrations;  // touched by the loader only

    const auto load = [&](std::size_t i) {
        LoadedFrame f;
        f.frame = frames[i];
        const auto start = Clock::now();
        try {
            const InputPaths paths = kitti_layout(a.kitti_root, f.frame);
            auto it = calibrations.find(paths.calibration);
            if (it == calibrations.end()) {
                it = calibrations
                         .emplace(paths.calibration,
                                  load_calibration(paths.calibration, options.calibration))
                         .first;
            }
            f.inputs = load_inputs(paths, options, it->second, palette);
        } catch (const std::exception& e) {
            f.error = e.what();
        }
        f.ms = ms_between(start, Clock::now());
        return f;
    };

    const std::size_t n = frames.size();
    const bool tty = isatty(STDERR_FILENO) != 0;
    ProgressMeter::Options progress_options;
    progress_options.terminal = tty;
    progress_options.line_interval_s = a.progress_every_s;
    ProgressMeter progress(label, n, progress_options);
    bool bar_open = false;  // a bar is drawn without its newline: an error line starts one
    std::size_t failed = 0;
    nlohmann::json failures = nlohmann::json::array();
    const auto fail = [&](const std::string& frame, const std::string& what) {
        ++failed;
        failures.push_back({{"frame", frame}, {"error", what}});
        std::fprintf(stderr, "%s%s: error: frame %s: %s\n", bar_open ? "\n" : "", kTool,
                     frame.c_str(), what.c_str());
        bar_open = false;
    };
    nlohmann::json per_frame = nlohmann::json::array();
    DisparityTally evaluation;
    std::future<LoadedFrame> next;
    if (n > 0) next = std::async(std::launch::async, load, 0);
    std::future<Finished> finishing;
    std::string finishing_frame;
    std::size_t finishing_record = 0;
    const auto collect = [&] {
        if (!finishing.valid()) return;
        const Finished done = finishing.get();
        per_frame[finishing_record]["finish_ms"] = done.ms;
        if (done.score) {
            evaluation.add(*done.score);
            per_frame[finishing_record]["d1_all"] = done.score->d1_all;
            per_frame[finishing_record]["epe_px"] = done.score->epe_px;
        }
        if (!done.evaluation_error.empty()) {
            std::fprintf(stderr, "%s%s: warning: frame %s: not scored: %s\n", bar_open ? "\n" : "",
                         kTool, finishing_frame.c_str(), done.evaluation_error.c_str());
            bar_open = false;
            per_frame[finishing_record]["evaluation_error"] = done.evaluation_error;
        }
        if (!done.error.empty()) {
            fail(finishing_frame, done.error);
            per_frame[finishing_record]["error"] = done.error;
        }
    };
    const auto start = Clock::now();
    const double cpu_start = cpu_seconds();
    const auto show_progress = [&](std::size_t done) {
        if (a.quiet) return;
        const std::string text =
            progress.update(done, failed, ms_between(start, Clock::now()) / 1000.0);
        if (text.empty()) return;
        std::fputs(text.c_str(), stderr);
        bar_open = text.back() != '\n';
    };
    for (std::size_t i = 0; i < n; ++i) {
        // The waits show whether the overlap works: with the loader and the finishing thread
        // keeping up, the main thread never waits for them and the frame period is the
        // matching stage's, whatever else runs on the machine.
        const auto wait_start = Clock::now();
        LoadedFrame frame = next.get();
        if (i + 1 < n) next = std::async(std::launch::async, load, i + 1);
        const auto t0 = Clock::now();
        nlohmann::json record = {{"frame", frame.frame},
                                 {"load_ms", frame.ms},
                                 {"wait_load_ms", ms_between(wait_start, t0)}};
        std::optional<FinishJob> job;
        if (!frame.inputs) {
            fail(frame.frame, frame.error);
            record["error"] = frame.error;
        } else {
            try {
                AnalyseResult r = analyse(*frame.inputs, options, matcher);
                for (const auto& s : r.timings) record[s.stage + "_ms"] = s.ms;
                record["points"] = r.cloud_points;
                const auto gt = a.kitti_root / "disp_occ_0" / (frame.frame + ".png");
                const bool scored = a.evaluate && std::filesystem::exists(gt);
                job = FinishJob{std::move(*frame.inputs),
                                std::move(r),
                                &a.settings,
                                &extract,
                                a.out_dir / frame.frame,
                                a.disparity_kitti,
                                a.cloud_formats,
                                scored ? gt : std::filesystem::path()};
            } catch (const std::exception& e) {
                fail(frame.frame, e.what());
                record["error"] = e.what();
            }
        }
        record["analyse_ms"] = ms_between(t0, Clock::now());
        record["rss_mb"] = current_rss_mb();
        per_frame.push_back(record);
        // One frame finishing at a time: frame n-1 must be done before frame n is handed over.
        const auto collect_start = Clock::now();
        collect();
        per_frame.back()["wait_finish_ms"] = ms_between(collect_start, Clock::now());
        if (job) {
            finishing_frame = frame.frame;
            finishing_record = per_frame.size() - 1;
            finishing = std::async(std::launch::async, finish_frame, std::move(*job));
        }
        show_progress(i + 1);
    }
    collect();
    const double seconds = ms_between(start, Clock::now()) / 1000.0;
    const double fps = seconds > 0.0 ? static_cast<double>(n) / seconds : 0.0;
    // CPU time per frame does not depend on what else runs on the machine; the busy share
    // (CPU time over wall time times cores) says whether the overlap keeps every core working.
    const double cpu = cpu_seconds() - cpu_start;
    const double cpu_ms_per_frame = n > 0 ? 1000.0 * cpu / static_cast<double>(n) : 0.0;
    const unsigned cores = std::max(1u, std::thread::hardware_concurrency());
    const double busy = cpu_ms_per_frame * fps / (1000.0 * cores);
    if (!a.quiet) {
        std::fprintf(stderr,
                     "%s%s: %zu frames in %.2f s (%.2f fps), %zu failed, peak RSS %.0f MB, "
                     "%.0f ms CPU per frame, cores %.0f %% busy\n",
                     bar_open ? "\n" : "", label.c_str(), n, seconds, fps, failed, peak_rss_mb(),
                     cpu_ms_per_frame, 100.0 * busy);
    }
    if (!a.report.empty()) {
        nlohmann::json report = {{"shard", {{"index", a.shard.index}, {"count", a.shard.count}}},
                                 {"list_frames", a.list_frames},
                                 {"frames", a.frames.size()},
                                 {"done", n - failed},
                                 {"skipped", skipped},
                                 {"failed", failed},
                                 {"failures", failures},
                                 {"started_at", started_at},
                                 {"ended_at", unix_seconds()},
                                 {"seconds", seconds},
                                 {"fps", fps},
                                 {"cpu_seconds", cpu},
                                 {"peak_rss_mb", peak_rss_mb()},
                                 {"cpu_ms_per_frame", cpu_ms_per_frame},
                                 {"cores", cores},
                                 {"cores_busy", busy},
                                 {"preset", a.settings.preset},
                                 {"per_frame", per_frame}};
        if (evaluation.frames > 0) report["evaluation"] = evaluation.to_json();
        write_output({a.report.string(), report.dump(1) + "\n", "--report"});
    }
    return failed == 0 ? 0 : 1;
}

CLI::App* add_report_command(CLI::App& app, ReportArgs& a) {
    CLI::App* cmd = app.add_subcommand(
        "report",
        "merge the reports of a sharded batch (batch --shard I/N --report) into one: frames "
        "done, skipped, failed with reasons, fps, CPU time, memory");
    cmd->add_option("reports", a.inputs, "shard report files")->required();
    cmd->add_option("--shards", a.shards, "shards of the run (default: as the reports say)")
        ->check(CLI::Range(1, 1000000));
    cmd->add_option("-o,--output", a.output, "merged report ('-' = stdout)")->capture_default_str();
    cmd->footer(
        "Exit 1 when a shard's report is missing or a frame failed (the report is "
        "still written), 2 on usage errors.");
    return cmd;
}

int run_report(const ReportArgs& a) {
    std::vector<nlohmann::json> reports;
    for (const auto& path : a.inputs) {
        std::ifstream in(path);
        if (!in)
            throw std::runtime_error("cannot read report: no such file (" + path.string() + ")");
        try {
            reports.push_back(nlohmann::json::parse(in));
        } catch (const nlohmann::json::exception& e) {
            throw std::runtime_error("cannot read report: " + std::string(e.what()) + " (" +
                                     path.string() + ")");
        }
    }
    int shards = a.shards;
    if (shards == 0 && !reports.empty() && reports.front().contains("shard")) {
        shards = reports.front()["shard"].value("count", 0);
    }
    nlohmann::json merged;
    try {
        merged = merge_batch_reports(reports, shards);
    } catch (const std::invalid_argument& e) {
        throw std::runtime_error(std::string("cannot merge reports: ") + e.what());
    }
    const std::string output_dir = std::filesystem::path(a.output).parent_path().string();
    if (a.output != "-" && !output_dir.empty() && !std::filesystem::is_directory(output_dir)) {
        throw std::runtime_error("cannot write output: no such folder (" + output_dir + ", -o)");
    }
    write_output({a.output, merged.dump(1) + "\n", "-o"});
    for (const auto& index : merged["missing_shards"]) {
        std::fprintf(stderr, "%s: error: shard %d/%d: no report\n", kTool, index.get<int>(),
                     shards);
    }
    for (const auto& f : merged["failures"]) {
        std::fprintf(stderr, "%s: error: frame %s: %s\n", kTool, f.value("frame", "?").c_str(),
                     f.value("error", "?").c_str());
    }
    std::fprintf(stderr,
                 "%s: report: %zu shards of %d, %zu frames: %zu done, %zu skipped (done "
                 "before), %zu failed; %.2f fps over %.1f s, %.0f ms CPU per frame, peak RSS "
                 "%.0f MB\n",
                 kTool, merged["shards_reported"].get<std::size_t>(), shards,
                 merged["frames"].get<std::size_t>(), merged["done"].get<std::size_t>(),
                 merged["skipped"].get<std::size_t>(), merged["failed"].get<std::size_t>(),
                 merged["fps"].get<double>(), merged["wall_seconds"].get<double>(),
                 merged["cpu_ms_per_frame"].get<double>(), merged["peak_rss_mb"].get<double>());
    if (merged.contains("evaluation")) {
        const auto& e = merged["evaluation"];
        std::fprintf(stderr,
                     "%s: report: disparity over %zu frames with ground truth: D1-all %.2f %%, "
                     "EPE %.2f px, density %.1f %%\n",
                     kTool, e["frames"].get<std::size_t>(), 100.0 * e["d1_all"].get<double>(),
                     e["epe_px"].get<double>(), 100.0 * e["density"].get<double>());
    }
    return merged["missing_shards"].empty() && merged["failed"].get<std::size_t>() == 0 ? 0 : 1;
}

CLI::App* add_bench_command(CLI::App& app, BenchArgs& a) {
    CLI::App* cmd = app.add_subcommand(
        "bench",
        "time one frame: per-stage medians of the real run (entities; entities + all three "
        "clouds), for frames from memory (as from a camera: the stages after decoding) and "
        "from PNG files (including decode), beside cv::StereoSGBM::compute alone on the same "
        "input in the same process, as JSON");
    add_input_flags(*cmd, a.analyse);
    add_settings_flags(*cmd, a.analyse);
    cmd->add_option("--runs", a.runs, "timed runs per row (median)")
        ->capture_default_str()
        ->check(CLI::Range(1, 1000));
    cmd->add_option("--warmup", a.warmup, "untimed runs before each row")
        ->capture_default_str()
        ->check(CLI::Range(0, 100));
    cmd->add_option("--work-dir", a.work_dir, "folder for the timed outputs")->required();
    cmd->add_option("--json", a.json, "result file ('-' = stdout)")->capture_default_str();
    return cmd;
}

int run_bench(const BenchArgs& a) {
    if (!std::filesystem::is_directory(a.work_dir)) {
        throw std::runtime_error("cannot write output: no such folder (" + a.work_dir.string() +
                                 ", --work-dir)");
    }
    // Two definitions of a frame's pipeline, measured side by side in one process:
    //  - memory: the frame is already decoded (as a camera delivers it); the stages after
    //    decoding, from the matcher to the written entity file (and clouds);
    //  - files: the same plus reading and decoding the PNG files and the class config.
    // The floor is the matcher call alone, on the views compute() prepares. It is timed
    // interleaved with the rows (matcher, row 1, ..., row 4, matcher, ...) so that all of them
    // see the same load of the machine over time. One matcher serves every row, as in a batch.
    DisparityMatcher matcher(a.analyse.options.disparity);
    std::vector<double> matcher_ms, matcher_cpu_ms;
    // Another matcher is timed beside cv::StereoSGBM with the same options, interleaved.
    const bool own_matcher = a.analyse.options.disparity.matcher != "sgbm";
    DisparityOptions reference_options = a.analyse.options.disparity;
    reference_options.matcher = "sgbm";
    std::optional<DisparityMatcher> reference;
    if (own_matcher) reference.emplace(reference_options);
    std::vector<double> reference_ms, reference_cpu_ms;

    struct Row {
        std::string input;  // "memory" or "files"
        std::string name;
        AnalyseArgs args;
        std::optional<LoadedRun> loaded;  // memory rows: decoded once, before timing
        std::map<std::string, std::vector<double>> stages;
        std::vector<std::string> order;
        std::vector<double> totals;
        std::vector<double> writes;  // atomic writes (the entity file fsync'ed): disk latency
        std::size_t points = 0;
    };
    std::vector<Row> rows;
    for (const char* input : {"memory", "files"}) {
        for (const bool clouds : {false, true}) {
            Row row;
            row.input = input;
            row.name = clouds ? "entities + xyz/pcd/ply" : "entities";
            row.args = a.analyse;
            row.args.timings = false;
            row.args.entities = (a.work_dir / "bench.json").string();
            if (clouds) {
                row.args.xyz = a.work_dir / "bench.xyz";
                row.args.pcd = a.work_dir / "bench.pcd";
                row.args.ply = a.work_dir / "bench.ply";
            }
            if (row.input == "memory") row.loaded = load_run(row.args);
            rows.push_back(std::move(row));
        }
    }
    const LoadedInputs& in = rows.front().loaded->inputs;

    for (int i = 0; i < a.warmup + a.runs; ++i) {
        const bool timed = i >= a.warmup;
        const auto time_one = [&](DisparityMatcher& m, std::vector<double>& wall,
                                  std::vector<double>& cpu) {
            const std::clock_t c0 = std::clock();  // process CPU time: all threads
            const double ms = m.time_matcher_only_ms(in.left, in.right);
            const double cpu_ms = 1000.0 * static_cast<double>(std::clock() - c0) / CLOCKS_PER_SEC;
            if (timed) {
                wall.push_back(ms);
                cpu.push_back(cpu_ms);
            }
        };
        time_one(matcher, matcher_ms, matcher_cpu_ms);
        if (reference) time_one(*reference, reference_ms, reference_cpu_ms);
        for (Row& row : rows) {
            // Every row reads the same frame: its warnings are said once, on the first run.
            row.args.warnings = i == 0 && &row == &rows.front();
            const auto t0 = Clock::now();
            const RunReport report = row.loaded
                                         ? analyse_loaded_and_write(*row.loaded, row.args, matcher)
                                         : analyse_and_write(row.args, matcher);
            const double total = ms_between(t0, Clock::now());
            row.points = report.points;
            if (!timed) continue;
            row.totals.push_back(total);
            double writes = 0.0;
            for (const auto& st : report.timings) {
                if (st.stage.rfind("write ", 0) == 0) writes += st.ms;
                if (row.stages.count(st.stage) == 0) row.order.push_back(st.stage);
                row.stages[st.stage].push_back(st.ms);
            }
            row.writes.push_back(writes);
        }
    }
    const double floor_ms = median(matcher_ms);
    nlohmann::json rows_json = nlohmann::json::array();
    for (Row& row : rows) {
        nlohmann::json stage_json = nlohmann::json::array();
        for (const auto& name : row.order) {
            stage_json.push_back({{"stage", name}, {"ms", median(row.stages[name])}});
        }
        const double total_ms = median(row.totals);
        rows_json.push_back({{"input", row.input},
                             {"row", row.name},
                             {"stages", stage_json},
                             {"total_ms", total_ms},
                             {"fps", 1000.0 / total_ms},
                             {"ratio_to_matcher", total_ms / floor_ms},
                             {"writes_ms", median(row.writes)},
                             {"points", row.points}});
    }
    const auto& d = a.analyse.options.disparity;
    const nlohmann::json result = {
        {"frame", in.paths.frame_id},
        {"width", in.left.width_px},
        {"height", in.left.height_px},
        {"preset", a.analyse.preset},
        {"num_disparities", d.num_disparities},
        {"block_size", d.block_size},
        {"mode", d.mode},
        {"downscale", d.downscale},
        {"runs", a.runs},
        {"warmup", a.warmup},
        {"inputs",
         {{"memory", "frames from memory (as from a camera): stages after decoding"},
          {"files", "frames from PNG files (including decode)"}}},
        {"matcher", d.matcher},
        {"matcher_ms", floor_ms},
        {"matcher_cpu_ms", median(matcher_cpu_ms)},
        {"reference_matcher_ms", own_matcher ? median(reference_ms) : floor_ms},
        {"reference_matcher_cpu_ms",
         own_matcher ? median(reference_cpu_ms) : median(matcher_cpu_ms)},
        {"rows", rows_json},
        {"peak_rss_mb", peak_rss_mb()}};
    write_output({a.json, result.dump(1) + "\n", "--json"});
    return 0;
}

}  // namespace cloud_analysis::app
