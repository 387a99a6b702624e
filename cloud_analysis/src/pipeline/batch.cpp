#include "cloud_analysis/pipeline/batch.hpp"

#include <sys/resource.h>

#include <algorithm>
#include <array>
#include <chrono>
#include <exception>
#include <fstream>
#include <future>
#include <map>
#include <memory>
#include <optional>
#include <stdexcept>
#include <thread>
#include <tuple>
#include <utility>

#include <scene_schema/entities.hpp>
#include <scene_schema/sequence.hpp>
#include <stereoscene/support/atomic_file.hpp>
#include <stereoscene/support/folder_lock.hpp>
#include <stereoscene/support/output_transaction.hpp>

#include "cloud_analysis/cloud/cloud_io.hpp"
#include "cloud_analysis/io/io.hpp"
#include "cloud_analysis/pipeline/rig_fit.hpp"
#include "cloud_analysis/stereo/calibration.hpp"
#include "cloud_analysis/stereo/disparity.hpp"

namespace cloud_analysis {
namespace {

using Clock = std::chrono::steady_clock;

double ms_between(Clock::time_point a, Clock::time_point b) {
    return std::chrono::duration<double, std::milli>(b - a).count();
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

/// The batch's settings fitted to one rig (fit_to_rig): frames of one calibration share them.
struct FittedRig {
    RigFit fit;
    AnalyseOptions analysis;  ///< fit.analyse, reprojecting by class when there are no clouds
    RunSettings run;          ///< the batch's, with the fitted settings and source.rig
};

/// One frame read from disk, or why it could not be.
struct LoadedFrame {
    std::string frame;
    std::optional<LoadedInputs> inputs;
    std::shared_ptr<const FittedRig> rig;  ///< with inputs
    std::string error;
    double ms = 0.0;
};

/// One analysed frame handed to the finishing thread: entity extraction, formatting, writing.
struct FinishJob {
    LoadedInputs in;
    std::shared_ptr<const FittedRig> rig;
    AnalyseResult result;
    std::filesystem::path stem;          ///< out-dir/<frame>
    std::filesystem::path gt_disparity;  ///< scored against when set (BatchOptions::evaluate)
    std::size_t position = 0;            ///< in the batch's frames (the drive's frame number)
};

/// What finishing a frame gave: an error text ("" when none) and its milliseconds.
struct Finished {
    std::string error;
    double ms = 0.0;
    std::optional<DisparityScore> score;  ///< with ground truth
    std::string evaluation_error;         ///< why the ground truth could not be used
};

/// One output file of a frame, formatted in memory before anything is written.
struct FrameOutput {
    std::filesystem::path path;
    std::string bytes;
    stereoscene::support::FileSync sync = stereoscene::support::FileSync::kDurable;
};

/// The camera's odometry over a batch: the poses of the frames written, in order.
struct Odometry {
    std::optional<odometry::VisualOdometry> chain;  ///< made with the first frame's camera
    std::vector<odometry::Pose> poses;              ///< of the frames written
    double resolution_scale = 1.0;                  ///< of the first frame's analysis
};

/// The pose of the frame of `job`, its motion chained onto the frames before it.
odometry::Pose pose_of(const FinishJob& job, const BatchOptions& options, Odometry& odo) {
    if (!odo.chain) {
        odo.chain.emplace(job.result.camera, options.odometry_options);
        odo.resolution_scale = job.in.resolution_scale;
    }
    return odo.chain->add(odometry_frame(job.in.left, job.in, job.result));
}

/// The frame's entity file: its entities with the drive's capture time and the camera's pose
/// when given, tracked when `sequence` is given.
std::string frame_entities(const FinishJob& job, const BatchOptions& options,
                           tracking::SequenceTracker* sequence,
                           const std::optional<odometry::Pose>& pose) {
    scene_schema::EntityDocument doc =
        entity_document(job.in, job.result, job.rig->fit.extract, job.rig->run);
    std::optional<double> time;
    if (job.position < options.drive.size()) time = options.drive[job.position].timestamp_s;
    if (time) doc.frame.timestamp_s = time;
    if (pose) doc.frame.pose = odometry::row_major(*pose);
    if (sequence != nullptr) {
        doc = sequence->track(doc, static_cast<std::int64_t>(job.position),
                              job.stem.filename().string() + ".json", time);
    }
    return scene_schema::dump_checked(doc);
}

/// Extracts the entities, formats every output and writes them, all or nothing, the entity
/// file last; with `sequence`, tracks the frame first and adds it to the index after.
Finished finish_frame(const FinishJob& job, const BatchOptions& options,
                      tracking::SequenceTracker* sequence, Odometry* odo) {
    const auto start = Clock::now();
    Finished done;
    try {
        // The entity file goes last: it marks the frame complete (a writer killed before it
        // leaves a frame that a resumed batch redoes).
        std::vector<FrameOutput> outputs;
        if (options.disparity_kitti) {
            outputs.push_back({job.stem.string() + "_disparity.png",
                               encode_kitti_disparity_png(job.result.disparity)});
        }
        std::optional<LabeledCloud> kept;  // the cloud files' points, when not all
        if (!options.cloud_drop_classes.empty()) {
            kept = without_classes(job.result.cloud,
                                   class_indices(job.in.palette, options.cloud_drop_classes));
        }
        const LabeledCloud& cloud = kept ? *kept : job.result.cloud;
        for (const auto& fmt : options.cloud_formats) {
            const std::filesystem::path path = job.stem.string() + "." + fmt;
            outputs.push_back({path,
                               format_cloud(cloud, job.in.palette, cloud_format_from_path(path)),
                               options.fsync_clouds ? stereoscene::support::FileSync::kDurable
                                                    : stereoscene::support::FileSync::kAtomicOnly});
        }
        std::optional<odometry::Pose> pose;
        if (odo != nullptr) pose = pose_of(job, options, *odo);
        outputs.push_back(
            {job.stem.string() + ".json", frame_entities(job, options, sequence, pose)});
        // One transaction: a frame's files are all written or none, and a failure restores
        // what a frame of an earlier run left there.
        stereoscene::support::OutputTransaction files;
        for (const auto& out : outputs) files.stage(out.path, out.bytes, out.sync);
        files.commit();
        if (pose) odo->poses.push_back(*pose);
        if (sequence != nullptr) sequence->commit(options.out_dir / "sequence.json");
    } catch (const std::exception& e) {
        done.error = e.what();
        if (sequence != nullptr) sequence->discard();
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

/// Decodes the frames of a KITTI-layout folder, each calibration file read and fitted once.
class FrameLoader {
  public:
    FrameLoader(const BatchOptions& options, const Palette& palette)
        : options_(options), analyse_(options.run.analyse), palette_(palette) {}

    LoadedFrame operator()(std::size_t i) {
        LoadedFrame f;
        f.frame = options_.frames[i];
        const auto start = Clock::now();
        try {
            InputPaths paths = options_.drive.empty() ? kitti_layout(options_.kitti_root, f.frame)
                                                      : options_.drive[i].paths;
            if (options_.drive.empty() && options_.kitti_instances) {
                paths.instance = kitti_instance_path(options_.kitti_root, f.frame);
            }
            auto it = calibrations_.find(paths.calibration);
            if (it == calibrations_.end()) {
                it = calibrations_
                         .emplace(paths.calibration,
                                  load_calibration(paths.calibration, analyse_.calibration))
                         .first;
            }
            f.inputs = load_inputs(paths, analyse_, it->second, palette_);
            f.rig = fitted(paths.calibration, *f.inputs);
        } catch (const std::exception& e) {
            f.error = e.what();
        }
        f.ms = ms_between(start, Clock::now());
        return f;
    }

  private:
    /// The settings fitted to the rig of `calibration` (as `in` has it, halved or not).
    std::shared_ptr<const FittedRig> fitted(const std::filesystem::path& calibration,
                                            const LoadedInputs& in) {
        const StereoCamera& c = in.calibration.camera;
        auto& rig = rigs_[{calibration, c.width_px, c.height_px}];
        if (rig) return rig;
        auto made = std::make_shared<FittedRig>();
        made->fit = fit_to_rig(analyse_, options_.extract, c);
        made->analysis = made->fit.run_options(palette_, !options_.cloud_formats.empty());
        made->run = made->fit.run_settings(options_.run, in);
        rig = made;
        return rig;
    }

    const BatchOptions& options_;
    const AnalyseOptions& analyse_;
    const Palette& palette_;
    std::map<std::filesystem::path, Calibration> calibrations_;  // used by one thread at a time
    // By calibration and analysed size; used by one thread at a time.
    std::map<std::tuple<std::filesystem::path, int, int>, std::shared_ptr<const FittedRig>> rigs_;
};

/// Matches a loaded frame (its stage timings and point count into `record`): the job that
/// finishes it, or nothing when it failed (reported to `fail` and recorded).
template <typename Fail>
std::optional<FinishJob> match(LoadedFrame& frame, std::optional<DisparityMatcher>& matcher,
                               const FittedRig*& matcher_rig, const BatchOptions& options,
                               nlohmann::json& record, Fail&& fail) {
    if (!frame.inputs) {
        fail(frame.frame, frame.error);
        record["error"] = frame.error;
        return std::nullopt;
    }
    try {
        // One matcher per rig, made again only when a frame brings another rig.
        if (matcher_rig != frame.rig.get()) {
            matcher.emplace(frame.rig->fit.analyse.disparity);
            matcher_rig = frame.rig.get();
        }
        AnalyseResult r = analyse(*frame.inputs, frame.rig->analysis, *matcher);
        for (const auto& s : r.timings) record[s.stage + "_ms"] = s.ms;
        std::vector<std::string> warnings = frame.rig->fit.warnings;
        for (auto& w : analysis_warnings(*frame.inputs, r)) warnings.push_back(std::move(w));
        const Calibration& calibration = frame.inputs->calibration;
        if (!calibration.note.empty()) {
            warnings.insert(warnings.begin(), calibration.note + " (" + calibration.source + ")");
        }
        if (!warnings.empty()) record["warnings"] = warnings;
        record["points"] = r.cloud_points;
        const auto gt = options.kitti_root / "disp_occ_0" / (frame.frame + ".png");
        const bool scored =
            options.evaluate && options.drive.empty() && std::filesystem::exists(gt);
        return FinishJob{std::move(*frame.inputs),
                         frame.rig,
                         std::move(r),
                         options.out_dir / frame.frame,
                         scored ? gt : std::filesystem::path(),
                         0};
    } catch (const std::exception& e) {
        fail(frame.frame, e.what());
        record["error"] = e.what();
        return std::nullopt;
    }
}

/// Counts a failed frame in the report and tells the observer.
void record_failure(BatchReport& report, const BatchObserver& observer, const std::string& frame,
                    const std::string& what) {
    ++report.failed;
    report.failures.push_back({{"frame", frame}, {"error", what}});
    if (observer.failed) observer.failed(frame, what);
}

/// Records what finishing `frame` gave in its per-frame `record` and the report's totals.
void record_finished(const Finished& done, const std::string& frame, nlohmann::json& record,
                     BatchReport& report, const BatchObserver& observer) {
    record["finish_ms"] = done.ms;
    if (done.score) {
        report.evaluation.add(*done.score);
        record["d1_all"] = done.score->d1_all;
        record["epe_px"] = done.score->epe_px;
    }
    if (!done.evaluation_error.empty()) {
        record["evaluation_error"] = done.evaluation_error;
        if (observer.not_scored) observer.not_scored(frame, done.evaluation_error);
    }
    if (!done.error.empty()) {
        record_failure(report, observer, frame, done.error);
        record["error"] = done.error;
    }
}

/// Fills the report's totals from the wall-clock start and the CPU time at the start.
void summarize(BatchReport& report, Clock::time_point start, double cpu_start) {
    const auto n = static_cast<double>(report.frames);
    report.seconds = ms_between(start, Clock::now()) / 1000.0;
    report.fps = report.seconds > 0.0 ? n / report.seconds : 0.0;
    // CPU time per frame does not depend on what else runs on the machine; the busy share
    // (CPU time over wall time times cores) says whether the overlap keeps every core working.
    report.cpu_seconds = cpu_seconds() - cpu_start;
    report.cpu_ms_per_frame = report.frames > 0 ? 1000.0 * report.cpu_seconds / n : 0.0;
    report.cores = std::max(1u, std::thread::hardware_concurrency());
    report.cores_busy = report.cpu_ms_per_frame * report.fps / (1000.0 * report.cores);
}

}  // namespace

odometry::OdometryFrame odometry_frame(const ImageU8& left, const LoadedInputs& in,
                                       const AnalyseResult& r) {
    std::vector<char> is_thing;
    for (const auto& c : in.palette.classes) is_thing.push_back(c.thing ? 1 : 0);
    return {odometry::grey_image(left), odometry::grey_image(in.right), r.disparity,
            odometry::static_mask(r.classes.class_index, is_thing)};
}

double peak_rss_mb() {
    rusage usage{};
    getrusage(RUSAGE_SELF, &usage);
    return static_cast<double>(usage.ru_maxrss) / 1024.0;  // ru_maxrss is in KiB on Linux
}

namespace {

/// Throws when the batch cannot start: no output folder, a drive whose ids and frames differ in
/// number, no folder to read frames from.
void check_batch(const BatchOptions& options) {
    if (!std::filesystem::is_directory(options.out_dir)) {
        throw std::runtime_error("cannot write output: no such folder (" +
                                 options.out_dir.string() + ")");
    }
    if (!options.drive.empty() && options.drive.size() != options.frames.size()) {
        throw std::invalid_argument("run_batch: the drive's frames and their ids differ in number");
    }
    // Nothing to read without frames (a resumed share already complete).
    if (options.drive.empty() && !options.frames.empty() &&
        !std::filesystem::is_directory(options.kitti_root)) {
        throw std::runtime_error("cannot read frames: no such folder (" +
                                 options.kitti_root.string() + ")");
    }
}

/// The output folder's lock: a second writer of the same frames is refused before any frame is
/// read.
stereoscene::support::FolderLock lock_output(const BatchOptions& options) {
    try {
        return stereoscene::support::FolderLock(options.out_dir, options.lock_name);
    } catch (const stereoscene::support::FileError& e) {
        throw std::runtime_error("cannot write output: the folder's lock is " + e.reason() +
                                 ", another batch is writing these frames (" + e.path().string() +
                                 ")");
    }
}

Palette batch_palette(const BatchOptions& options) {
    try {
        return load_palette(options.run.analyse.palette);
    } catch (const std::exception& e) {
        throw std::runtime_error(std::string("cannot read palette: ") + e.what());
    }
}

/// After the last frame: the drive's sequence index and the poses, then the report's totals.
void end_batch(const BatchOptions& options, std::optional<tracking::SequenceTracker>& sequence,
               const std::optional<Odometry>& odo, BatchReport& report, Clock::time_point start,
               double cpu_start) {
    if (sequence) {
        sequence->commit(options.out_dir / "sequence.json",
                         stereoscene::support::FileSync::kDurable);
        report.tracking = sequence->report();
    }
    if (odo) {
        stereoscene::support::write_file_atomic(options.out_dir / "poses.txt",
                                                odometry::format_kitti_poses(odo->poses));
        if (odo->chain && options.odometry_options.estimate_disparity_offset) {
            // The rig's offset in full-resolution pixels: the one the analysis was given plus
            // what the motion still measures at the analysed resolution.
            report.disparity_offset_px = options.run.analyse.calibration.disparity_offset_px +
                                         odo->chain->disparity_offset_px() / odo->resolution_scale;
        }
    }
    summarize(report, start, cpu_start);
}

}  // namespace

BatchReport run_batch(const BatchOptions& options, const BatchObserver& observer) {
    check_batch(options);
    const stereoscene::support::FolderLock lock = lock_output(options);
    const Palette palette = batch_palette(options);
    // Made with the first frame's rig (FittedRig).
    std::optional<DisparityMatcher> matcher;
    const FittedRig* matcher_rig = nullptr;
    FrameLoader load(options, palette);
    std::optional<tracking::SequenceTracker> sequence;
    if (options.track) {
        sequence.emplace(options.sequence_id, options.track->fps, *options.track,
                         [&](const std::string& warning) {
                             if (observer.warning) observer.warning(warning);
                         });
    }

    std::optional<Odometry> odo;
    if (options.odometry) odo.emplace();

    BatchReport report;
    const std::size_t n = options.frames.size();
    report.frames = n;
    const auto fail = [&](const std::string& frame, const std::string& what) {
        record_failure(report, observer, frame, what);
    };
    auto& per_frame = report.per_frame;
    std::future<LoadedFrame> next;
    if (n > 0) next = std::async(std::launch::async, std::ref(load), 0);
    std::future<Finished> finishing;
    std::string finishing_frame;
    std::size_t finishing_record = 0;
    const auto collect = [&] {
        if (!finishing.valid()) return;
        record_finished(finishing.get(), finishing_frame, per_frame[finishing_record], report,
                        observer);
    };
    const auto start = Clock::now();
    const double cpu_start = cpu_seconds();
    for (std::size_t i = 0; i < n; ++i) {
        // The waits show whether the overlap works: with the loader and the finishing thread
        // keeping up, the main thread never waits for them and the frame period is the
        // matching stage's, whatever else runs on the machine.
        const auto wait_start = Clock::now();
        LoadedFrame frame = next.get();
        if (i + 1 < n) next = std::async(std::launch::async, std::ref(load), i + 1);
        const auto t0 = Clock::now();
        nlohmann::json record = {{"frame", frame.frame},
                                 {"load_ms", frame.ms},
                                 {"wait_load_ms", ms_between(wait_start, t0)}};
        std::optional<FinishJob> job = match(frame, matcher, matcher_rig, options, record, fail);
        record["analyse_ms"] = ms_between(t0, Clock::now());
        record["rss_mb"] = current_rss_mb();
        per_frame.push_back(record);
        // One frame finishing at a time: frame n-1 must be done before frame n is handed over.
        const auto collect_start = Clock::now();
        collect();
        per_frame.back()["wait_finish_ms"] = ms_between(collect_start, Clock::now());
        if (job) {
            job->position = i;
            finishing_frame = frame.frame;
            finishing_record = per_frame.size() - 1;
            finishing =
                std::async(std::launch::async, [&options, &sequence, &odo, j = std::move(*job)] {
                    return finish_frame(j, options, sequence ? &*sequence : nullptr,
                                        odo ? &*odo : nullptr);
                });
        }
        if (observer.progress) {
            observer.progress(i + 1, n, report.failed, ms_between(start, Clock::now()) / 1000.0);
        }
    }
    collect();
    end_batch(options, sequence, odo, report, start, cpu_start);
    return report;
}

}  // namespace cloud_analysis
