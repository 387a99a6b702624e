#include "analyse.hpp"

#include <chrono>
#include <cstdio>
#include <iostream>
#include <optional>

#include <scene_schema/entities.hpp>
#include <stereoscene/support/output_transaction.hpp>

#include "cloud_analysis/cloud/cloud_io.hpp"
#include "cloud_analysis/entities/extract.hpp"
#include "cloud_analysis/geometry/scene_geometry.hpp"
#include "cloud_analysis/pipeline/entity_document.hpp"
#include "output.hpp"

namespace cloud_analysis::app {

CLI::App* add_analyse_command(CLI::App& app, AnalyseArgs& args) {
    CLI::App* analyse = app.add_subcommand(
        "analyse", "stereo pair -> disparity -> cloud -> entities (the default command)");
    add_input_flags(*analyse, args);
    add_settings_flags(*analyse, args);
    add_output_flags(*analyse, args);
    analyse->footer(
        "Other commands: evaluate, export-kitti, make-sample, batch, report, bench (each with "
        "--help).\n"
        "Exit codes: 0 ok, 1 failure (one line on stderr, no output written), 2 usage error.");
    return analyse;
}

LoadedRun load_run(const AnalyseArgs& a) {
    // Validate everything before the expensive stages.
    const std::vector<std::pair<std::filesystem::path, const char*>> clouds = {
        {a.xyz, "--xyz"}, {a.pcd, "--pcd"}, {a.ply, "--ply"}};
    for (const auto& [path, flag] : clouds) {
        if (path.empty()) continue;
        try {
            cloud_analysis::cloud_format_from_path(path);
        } catch (const std::invalid_argument& e) {
            throw CLI::ValidationError(flag, e.what());
        }
    }
    const std::vector<std::pair<std::string, const char*>> all_outputs = {
        {a.entities, "--entities"},
        {a.xyz.string(), "--xyz"},
        {a.pcd.string(), "--pcd"},
        {a.ply.string(), "--ply"},
        {a.disparity_png.string(), "--disparity-png"},
        {a.disparity_kitti.string(), "--disparity-kitti"},
        {a.semantic_out.string(), "--semantic-out"},
        {a.segments_out.string(), "--segments-out"},
        {a.segment_ids_out.string(), "--segment-ids-out"}};
    int to_stdout = 0;
    // Declared on a transaction only to refuse a directory, a missing folder or one file named
    // by two flags before any work; nothing is staged on it.
    stereoscene::support::OutputTransaction check;
    for (const auto& [path, flag] : all_outputs) {
        if (path.empty()) continue;
        if (path == "-") {
            if (++to_stdout > 1) {
                throw CLI::ValidationError(flag, "only one output can go to stdout ('-')");
            }
            continue;
        }
        try {
            check.declare(path, flag);
        } catch (const stereoscene::support::FileError& e) {
            throw std::runtime_error("cannot write output: " + e.reason() + " (" + path + ", " +
                                     flag + ")");
        }
    }
    LoadedRun run{{}, extract_options(a), {}, std::nullopt};
    run.inputs = cloud_analysis::load_inputs(a.paths, a.options);
    run.fit = cloud_analysis::fit_to_rig(a.options, run.extract, run.inputs.calibration.camera);
    if ((!a.segments_out.empty() || !a.segment_ids_out.empty()) &&
        cloud_analysis::semantics_path(run.inputs, a.options) != "geometry") {
        throw std::runtime_error(
            std::string("no segments: the classes come from the semantic image; ") +
            (a.segments_out.empty() ? "--segment-ids-out" : "--segments-out") +
            " needs --semantics geometry");
    }
    if (!a.gt_disparity.empty()) {
        run.gt_disparity = cloud_analysis::read_kitti_disparity(a.gt_disparity);
        const auto& gt = *run.gt_disparity;
        const auto& cam = run.inputs.calibration.camera;
        if (gt.width_px != cam.width_px || gt.height_px != cam.height_px) {
            throw std::runtime_error(
                "inputs do not match: GT disparity is " + std::to_string(gt.width_px) + "x" +
                std::to_string(gt.height_px) + ", rectified images are " +
                std::to_string(cam.width_px) + "x" + std::to_string(cam.height_px) + " (" +
                a.gt_disparity.string() + ")");
        }
    }
    return run;
}

namespace {

using Clock = std::chrono::steady_clock;

double ms_since(Clock::time_point t) {
    return std::chrono::duration<double, std::milli>(Clock::now() - t).count();
}

/// The inputs' and the analysis's warnings, and the disparity's scores against --gt-disparity,
/// to stderr.
void report_analysis(const LoadedRun& run, const cloud_analysis::AnalyseResult& r,
                     const AnalyseArgs& a) {
    if (a.warnings) {
        for (const auto& w : run.fit.warnings) std::cerr << kTool << ": warning: " << w << "\n";
        for (const auto& w : cloud_analysis::analysis_warnings(run.inputs, r)) {
            std::cerr << kTool << ": warning: " << w << "\n";
        }
    }
    if (run.gt_disparity) {
        const auto s = cloud_analysis::score_disparity(r.disparity, *run.gt_disparity);
        const auto& bands = cloud_analysis::DisparityScore::kBiasBandsPx;
        std::fprintf(stderr,
                     "%s: disparity vs %s: D1-all %.2f %%, D1-valid %.2f %%, EPE %.3f px, "
                     "density %.2f %% (%zu GT px), bias %+.2f / %+.2f / %+.2f px (d < %g / "
                     "%g-%g / >= %g px)\n",
                     kTool, a.gt_disparity.string().c_str(), 100.0 * s.d1_all, 100.0 * s.d1_valid,
                     s.epe_px, 100.0 * s.density, s.gt_pixels, s.bias_px[0], s.bias_px[1],
                     s.bias_px[2], bands[0], bands[0], bands[1], bands[1]);
    }
}

/// The per-pixel classes the analysis used, in the palette's colours, as a PNG (every pixel void
/// when there were none).
std::string encode_semantic_png(const cloud_analysis::AnalyseResult& r,
                                const cloud_analysis::Palette& palette) {
    cloud_analysis::ClassImage classes = r.classes;
    if (classes.class_index.empty()) {
        classes.width_px = r.camera.width_px;
        classes.height_px = r.camera.height_px;
        classes.class_index.assign(static_cast<std::size_t>(classes.width_px) * classes.height_px,
                                   cloud_analysis::kVoidClass);
    }
    return cloud_analysis::encode_png(cloud_analysis::geometry::colour_classes(classes, palette));
}

/// Every output the flags ask for, formatted in memory (each step's time into `timings`).
std::vector<PendingOutput> format_outputs(const LoadedRun& run,
                                          const cloud_analysis::AnalyseResult& r,
                                          const AnalyseArgs& a,
                                          std::vector<cloud_analysis::StageTiming>& timings) {
    const cloud_analysis::LoadedInputs& in = run.inputs;
    std::vector<PendingOutput> outputs;
    auto t = Clock::now();
    if (!a.entities.empty()) {
        outputs.push_back({a.entities,
                           cloud_analysis::entity_json(in, r, run.fit.extract,
                                                       run.fit.run_settings(run_settings(a), in)),
                           "--entities"});
        timings.push_back({"entities", ms_since(t)});
    }
    const std::vector<std::pair<std::filesystem::path, const char*>> clouds = {
        {a.xyz, "--xyz"}, {a.pcd, "--pcd"}, {a.ply, "--ply"}};
    std::optional<cloud_analysis::LabeledCloud> kept;  // the cloud files' points, when not all
    if (!a.drop_classes.empty()) {
        kept = cloud_analysis::without_classes(
            r.cloud, cloud_analysis::class_indices(in.palette, a.drop_classes));
    }
    const cloud_analysis::LabeledCloud& cloud = kept ? *kept : r.cloud;
    for (const auto& [path, flag] : clouds) {
        if (path.empty()) continue;
        t = Clock::now();
        outputs.push_back({path.string(),
                           cloud_analysis::format_cloud(
                               cloud, in.palette, cloud_analysis::cloud_format_from_path(path)),
                           flag, cloud_sync(a)});
        timings.push_back({std::string("format ") + flag, ms_since(t)});
    }
    t = Clock::now();
    if (!a.disparity_png.empty()) {
        outputs.push_back({a.disparity_png.string(),
                           cloud_analysis::encode_disparity_preview_png(
                               r.disparity, a.options.disparity.min_disparity +
                                                a.options.disparity.num_disparities),
                           "--disparity-png"});
    }
    if (!a.disparity_kitti.empty()) {
        outputs.push_back({a.disparity_kitti.string(),
                           cloud_analysis::encode_kitti_disparity_png(r.disparity),
                           "--disparity-kitti"});
    }
    if (!a.disparity_png.empty() || !a.disparity_kitti.empty()) {
        timings.push_back({"encode disparity", ms_since(t)});
    }
    if (!a.semantic_out.empty()) {
        t = Clock::now();
        outputs.push_back(
            {a.semantic_out.string(), encode_semantic_png(r, in.palette), "--semantic-out"});
        timings.push_back({"encode semantic", ms_since(t)});
    }
    // load_run refused these flags unless the geometry makes the classes.
    if (r.geometry && (!a.segments_out.empty() || !a.segment_ids_out.empty())) {
        t = Clock::now();
        if (!a.segments_out.empty()) {
            outputs.push_back(
                {a.segments_out.string(),
                 cloud_analysis::geometry::segments_json(*r.geometry, in.paths.frame_id),
                 "--segments-out"});
        }
        if (!a.segment_ids_out.empty()) {
            outputs.push_back({a.segment_ids_out.string(),
                               cloud_analysis::encode_png_u16(cloud_analysis::geometry::segment_ids(
                                   *r.geometry, r.camera.width_px, r.camera.height_px)),
                               "--segment-ids-out"});
        }
        timings.push_back({"format segments", ms_since(t)});
    }
    return outputs;
}

/// Writes every output as one transaction, all or nothing: the files are staged beside their
/// targets, standard output is written, then the files are committed; on any failure the
/// earlier files are back in place (each write's time into `timings`).
void write_all(const std::vector<PendingOutput>& outputs,
               std::vector<cloud_analysis::StageTiming>& timings) {
    stereoscene::support::OutputTransaction files;
    const PendingOutput* to_stdout = nullptr;
    try {
        for (const auto& out : outputs) {
            if (out.path == "-") {
                to_stdout = &out;
                continue;
            }
            const auto t = Clock::now();
            files.stage(out.path, out.bytes, out.sync);
            timings.push_back({"write " + out.label, ms_since(t)});
        }
        if (to_stdout != nullptr) write_output(*to_stdout);
        files.commit();
    } catch (const stereoscene::support::FileError& e) {
        throw std::runtime_error("cannot write output: " + e.reason() + " (" + e.path().string() +
                                 ")");
    }
}

}  // namespace

RunReport analyse_loaded_and_write(const LoadedRun& run, const AnalyseArgs& a,
                                   cloud_analysis::DisparityMatcher& matcher) {
    const cloud_analysis::LoadedInputs& in = run.inputs;
    std::vector<cloud_analysis::StageTiming> timings;
    if (a.warnings && !in.calibration.note.empty()) {
        std::cerr << kTool << ": warning: " << in.calibration.note << " (" << in.calibration.source
                  << ")\n";
    }
    const bool any_cloud = !a.xyz.empty() || !a.pcd.empty() || !a.ply.empty();
    cloud_analysis::AnalyseResult r =
        cloud_analysis::analyse(in, run.fit.run_options(in.palette, any_cloud), matcher);
    timings.insert(timings.end(), r.timings.begin(), r.timings.end());
    report_analysis(run, r, a);
    const std::vector<PendingOutput> outputs = format_outputs(run, r, a, timings);
    // Every output exists in memory now: only writing is left.
    write_all(outputs, timings);
    return {timings, r.cloud_points};
}

namespace {

/// load_run, then the stages after it with `matcher` or, when null, a matcher of the run's own
/// fitted options; the first timing is "load".
RunReport load_analyse_and_write(const AnalyseArgs& a, cloud_analysis::DisparityMatcher* matcher) {
    const auto start = std::chrono::steady_clock::now();
    const LoadedRun run = load_run(a);
    const double load_ms = ms_since(start);
    std::optional<cloud_analysis::DisparityMatcher> own;
    if (matcher == nullptr) matcher = &own.emplace(run.fit.analyse.disparity);
    RunReport report = analyse_loaded_and_write(run, a, *matcher);
    report.timings.insert(report.timings.begin(), {"load", load_ms});
    return report;
}

}  // namespace

RunReport analyse_and_write(const AnalyseArgs& a, cloud_analysis::DisparityMatcher& matcher) {
    return load_analyse_and_write(a, &matcher);
}

RunReport analyse_and_write(const AnalyseArgs& a) { return load_analyse_and_write(a, nullptr); }

int run_analyse(const AnalyseArgs& a) {
    const RunReport report = analyse_and_write(a);
    if (a.timings) {
        double total = 0.0;
        for (const auto& s : report.timings) {
            std::fprintf(stderr, "%s: timing: %-22s %9.1f ms\n", kTool, s.stage.c_str(), s.ms);
            total += s.ms;
        }
        std::fprintf(stderr, "%s: timing: %-22s %9.1f ms (%zu points)\n", kTool, "total", total,
                     report.points);
    }
    return 0;
}

}  // namespace cloud_analysis::app
