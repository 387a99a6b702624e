#include "bench.hpp"

#include <algorithm>
#include <chrono>
#include <ctime>
#include <map>
#include <optional>
#include <stdexcept>
#include <vector>

#include <nlohmann/json.hpp>

#include "analyse.hpp"
#include "cloud_analysis/io/io.hpp"
#include "cloud_analysis/pipeline/batch.hpp"
#include "cloud_analysis/stereo/disparity.hpp"
#include "cloud_analysis/support/select.hpp"
#include "output.hpp"

namespace cloud_analysis::app {
namespace {

using Clock = std::chrono::steady_clock;

double ms_between(Clock::time_point a, Clock::time_point b) {
    return std::chrono::duration<double, std::milli>(b - a).count();
}

/// Process CPU time (all threads) since `start`, ms.
double cpu_ms_since(std::clock_t start) {
    return 1000.0 * static_cast<double>(std::clock() - start) / CLOCKS_PER_SEC;
}

/// One timed configuration: frames from memory or from files, with or without clouds.
struct Row {
    std::string input;  // "memory" or "files"
    std::string name;
    AnalyseArgs args;
    std::optional<LoadedRun> loaded;  // memory rows: decoded once, before timing
    std::map<std::string, std::vector<double>> stages;
    std::vector<std::string> order;
    std::vector<double> totals;
    std::vector<double> cpu;     // process CPU (all threads), ms per run
    std::vector<double> writes;  // atomic writes (the entity file fsync'ed): disk latency
    std::size_t points = 0;
};

/// The four rows, memory rows decoded.
std::vector<Row> make_rows(const BenchArgs& a) {
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
    return rows;
}

/// Runs every row once (timed or not) with `matcher`.
void run_rows(std::vector<Row>& rows, bool timed, bool first, DisparityMatcher& matcher) {
    for (Row& row : rows) {
        // Every row reads the same frame: its warnings are said once, on the first run.
        row.args.warnings = first && &row == &rows.front();
        const std::clock_t c0 = std::clock();
        const auto t0 = Clock::now();
        const RunReport report = row.loaded
                                     ? analyse_loaded_and_write(*row.loaded, row.args, matcher)
                                     : analyse_and_write(row.args, matcher);
        const double total = ms_between(t0, Clock::now());
        const double cpu = cpu_ms_since(c0);
        row.points = report.points;
        if (!timed) continue;
        row.totals.push_back(total);
        row.cpu.push_back(cpu);
        double writes = 0.0;
        for (const auto& st : report.timings) {
            if (st.stage.rfind("write ", 0) == 0) writes += st.ms;
            if (row.stages.count(st.stage) == 0) row.order.push_back(st.stage);
            row.stages[st.stage].push_back(st.ms);
        }
        row.writes.push_back(writes);
    }
}

/// The rows' medians as JSON.
nlohmann::json rows_json(std::vector<Row>& rows, double floor_ms) {
    nlohmann::json out = nlohmann::json::array();
    for (Row& row : rows) {
        nlohmann::json stage_json = nlohmann::json::array();
        for (const auto& name : row.order) {
            stage_json.push_back({{"stage", name}, {"ms", median(row.stages[name])}});
        }
        const double total_ms = median(row.totals);
        out.push_back({{"input", row.input},
                       {"row", row.name},
                       {"stages", stage_json},
                       {"total_ms", total_ms},
                       {"cpu_ms", median(row.cpu)},
                       {"fps", 1000.0 / total_ms},
                       {"ratio_to_matcher", total_ms / floor_ms},
                       {"writes_ms", median(row.writes)},
                       {"points", row.points}});
    }
    return out;
}

/// Matcher-only times of one matcher: wall and process CPU (all threads), ms per run.
struct MatcherTimes {
    std::vector<double> wall_ms, cpu_ms;

    void time(DisparityMatcher& m, const LoadedInputs& in, bool timed) {
        const std::clock_t c0 = std::clock();
        const double ms = m.time_matcher_only_ms(in.left, in.right);
        const double cpu = cpu_ms_since(c0);
        if (!timed) return;
        wall_ms.push_back(ms);
        cpu_ms.push_back(cpu);
    }
};

/// The odometry's cost per frame in a drive: the frame as batch --odometry hands it over
/// (odometry_frame) and VisualOdometry::add from it to the next frame (its motion, the next
/// frame's pyramid); wall and process CPU time (all threads), ms per run. With the frame
/// before (`prev`), the odometry first moves from it, as a batch's does after its first frame.
class OdometryTimes {
  public:
    /// `r`: the frame analysed; `next_left`: the next frame's left image (same size); `prev`:
    /// the frame before, analysed, when given.
    OdometryTimes(const LoadedInputs& in, AnalyseResult r, ImageU8 next_left,
                  std::optional<std::pair<LoadedInputs, AnalyseResult>> prev)
        : in_(in), r_(std::move(r)), next_left_(std::move(next_left)), prev_(std::move(prev)) {
        const auto differs = [&](const ImageU8& image) {
            return image.width_px != in.left.width_px || image.height_px != in.left.height_px;
        };
        if (differs(next_left_)) {
            throw std::runtime_error(
                "the next frame's left image differs in size from --left "
                "(--next-left)");
        }
        if (prev_ && differs(prev_->first.left)) {
            throw std::runtime_error(
                "the frame before differs in size from --left (--prev-left, --prev-right)");
        }
    }

    void time(bool timed) {
        odometry::VisualOdometry vo(r_.camera, odometry::OdometryOptions{});
        if (prev_) vo.add(odometry_frame(prev_->first.left, prev_->first, prev_->second));
        vo.add(odometry_frame(in_.left, in_, r_));
        const std::clock_t c0 = std::clock();
        const auto t0 = Clock::now();
        vo.add(odometry_frame(next_left_, in_, r_));
        const double ms = ms_between(t0, Clock::now());
        const double cpu = cpu_ms_since(c0);
        if (!timed) return;
        wall_ms.push_back(ms);
        cpu_ms.push_back(cpu);
    }

    std::vector<double> wall_ms, cpu_ms;

  private:
    const LoadedInputs& in_;
    AnalyseResult r_;
    ImageU8 next_left_;
    std::optional<std::pair<LoadedInputs, AnalyseResult>> prev_;
};

/// The drive's frame before this one (--prev-left, --prev-right), loaded and analysed as
/// `args` would be; it has a pair and no class or instance image of its own.
std::pair<LoadedInputs, AnalyseResult> frame_before(const BenchArgs& a, AnalyseArgs args,
                                                    DisparityMatcher& matcher) {
    args.paths.left = a.prev_left;
    args.paths.right = a.prev_right;
    args.paths.semantic.clear();
    args.paths.instance.clear();
    try {
        LoadedRun p = load_run(args);
        AnalyseResult r = analyse(p.inputs, p.fit.run_options(p.inputs.palette, false), matcher);
        return {std::move(p.inputs), std::move(r)};
    } catch (const std::exception& e) {
        throw std::runtime_error(std::string("the frame before (--prev-left, --prev-right): ") +
                                 e.what());
    }
}

}  // namespace

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
    cmd->add_option("--next-left", a.next_left,
                    "the next frame's left image of a drive: also time the odometry's cost per "
                    "frame (batch --odometry) in the same process");
    cmd->add_option("--prev-left", a.prev_left,
                    "the frame before this one in the drive, left image: the odometry moves "
                    "from it first, as in a batch after its first frame (with --next-left)");
    cmd->add_option("--prev-right", a.prev_right,
                    "the frame before's right image (--prev-left); that frame is analysed from "
                    "its pair alone");
    return cmd;
}

int run_bench(const BenchArgs& a) {
    if (a.prev_left.empty() != a.prev_right.empty()) {
        throw std::runtime_error("--prev-left and --prev-right go together");
    }
    if (!a.prev_left.empty() && a.next_left.empty()) {
        throw std::runtime_error("--prev-left needs --next-left (the odometry's frames)");
    }
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
    // Another matcher than cv::StereoSGBM is timed beside it with the same options, interleaved.
    std::vector<Row> rows = make_rows(a);
    const LoadedInputs& in = rows.front().loaded->inputs;
    const DisparityOptions& d = rows.front().loaded->fit.analyse.disparity;  // fitted to the rig
    DisparityMatcher matcher(d);
    const bool own_matcher = d.matcher != "sgbm";
    DisparityOptions reference_options = d;
    reference_options.matcher = "sgbm";
    std::optional<DisparityMatcher> reference;
    if (own_matcher) reference.emplace(reference_options);
    MatcherTimes matcher_times, reference_times;
    std::optional<OdometryTimes> odometry_times;
    if (!a.next_left.empty()) {
        const LoadedRun& run = *rows.front().loaded;
        std::optional<std::pair<LoadedInputs, AnalyseResult>> prev;
        if (!a.prev_left.empty()) prev = frame_before(a, rows.front().args, matcher);
        odometry_times.emplace(in, analyse(in, run.fit.run_options(in.palette, false), matcher),
                               read_image(a.next_left), std::move(prev));
    }
    for (int i = 0; i < a.warmup + a.runs; ++i) {
        const bool timed = i >= a.warmup;
        matcher_times.time(matcher, in, timed);
        if (reference) reference_times.time(*reference, in, timed);
        if (odometry_times) odometry_times->time(timed);
        run_rows(rows, timed, i == 0, matcher);
    }
    const double floor_ms = median(matcher_times.wall_ms);
    const MatcherTimes& ref = own_matcher ? reference_times : matcher_times;
    nlohmann::json result = {
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
        {"matcher_cpu_ms", median(matcher_times.cpu_ms)},
        {"reference_matcher_ms", median(ref.wall_ms)},
        {"reference_matcher_cpu_ms", median(ref.cpu_ms)},
        {"rows", rows_json(rows, floor_ms)},
        {"peak_rss_mb", cloud_analysis::peak_rss_mb()}};
    if (odometry_times) {
        result["odometry_ms"] = median(odometry_times->wall_ms);
        result["odometry_cpu_ms"] = median(odometry_times->cpu_ms);
    }
    write_output({a.json, result.dump(1) + "\n", "--json"});
    return 0;
}

}  // namespace cloud_analysis::app
