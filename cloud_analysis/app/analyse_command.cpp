#include "analyse_command.hpp"

#include <chrono>
#include <cstdio>
#include <cstring>
#include <iostream>
#include <optional>
#include <set>

#include <scene_schema/entities.hpp>

#include "cloud_analysis/cloud/cloud_io.hpp"
#include "cloud_analysis/entities/extract.hpp"
#include "cloud_analysis/stereo/disparity.hpp"

namespace cloud_analysis::app {

void add_input_flags(CLI::App& cmd, AnalyseArgs& a) {
    const std::string in = "Inputs";
    cmd.add_option("--left,-l", a.paths.left, "left rectified image (PNG/JPG)")->group(in);
    cmd.add_option("--right,-r", a.paths.right, "right rectified image")->group(in);
    cmd.add_option("--semantic,-s", a.paths.semantic, "semantic colour image of the left view")
        ->group(in);
    cmd.add_option("--calib,-c", a.paths.calibration,
                   "calibration: KITTI calib_cam_to_cam.txt, KITTI object calib, or YAML/JSON "
                   "(fx fy cx cy baseline_m [distortion])")
        ->group(in);
    cmd.add_option("--kitti-root", a.kitti_root,
                   "KITTI folder: image_2/ image_3/ semantic_rgb/ calib/ (with --frame)")
        ->group(in);
    cmd.add_option("--frame", a.frame, "frame id, e.g. 000000_10 (names the entity frame)")
        ->group(in);
}

void add_settings_flags(CLI::App& cmd, AnalyseArgs& a) {
    auto& d = a.options.disparity;
    const std::string in = "Inputs";
    cmd.add_flag("--raw", a.options.raw,
                 "inputs are unrectified: undistort and rectify with K/D/R_rect first")
        ->group(in);
    cmd.add_option("--left-camera", a.options.calibration.left_camera,
                   "KITTI camera index of the left image")
        ->capture_default_str()
        ->group(in);
    cmd.add_option("--right-camera", a.options.calibration.right_camera,
                   "KITTI camera index of the right image")
        ->capture_default_str()
        ->group(in);
    cmd.add_option("--semantics", a.options.semantics,
                   "classes from: labels (the semantic image), geometry (the stereo pair alone, "
                   "docs/stereo-only.md) or auto (labels when a semantic image is given)")
        ->check(CLI::IsMember({"labels", "geometry", "auto"}))
        ->capture_default_str()
        ->group(in);
    cmd.add_option("--palette", a.options.palette,
                   "semantic palette: cityscapes, carla, thesis or a palette JSON file")
        ->capture_default_str()
        ->group(in);

    const std::string sg = "Disparity (cv::StereoSGBM)";
    cmd.add_option("--preset", a.preset,
                   "starting values: tuned (KITTI-tuned defaults), fast (half-resolution "
                   "matching), quality (tuned + WLS) or opencv-sample "
                   "(samples/cpp/stereo_match.cpp); flags below override (docs/performance.md)")
        ->check(CLI::IsMember({"tuned", "fast", "quality", "opencv-sample"}))
        ->capture_default_str()
        ->group(sg);
    cmd.add_option("--min-disparity", d.min_disparity, "smallest disparity, px")
        ->capture_default_str()
        ->group(sg);
    cmd.add_option("--num-disparities", d.num_disparities, "search range, px, multiple of 16")
        ->capture_default_str()
        ->group(sg);
    cmd.add_option("--block-size", d.block_size, "matching window, px, odd")
        ->capture_default_str()
        ->group(sg);
    cmd.add_option("--p1", d.p1, "penalty of +-1 px changes (0 = 8*cn*block^2)")
        ->capture_default_str()
        ->group(sg);
    cmd.add_option("--p2", d.p2, "penalty of larger changes (0 = 32*cn*block^2)")
        ->capture_default_str()
        ->group(sg);
    cmd.add_option("--disp12-max-diff", d.disp12_max_diff,
                   "SGBM internal left-right check, px (<0 off)")
        ->capture_default_str()
        ->group(sg);
    cmd.add_option("--pre-filter-cap", d.pre_filter_cap, "prefilter clip, 1..63")
        ->capture_default_str()
        ->group(sg);
    cmd.add_option("--uniqueness-ratio", d.uniqueness_ratio, "uniqueness margin, %")
        ->capture_default_str()
        ->group(sg);
    cmd.add_option("--speckle-window-size", d.speckle_window_size,
                   "largest speckle removed, px (0 off)")
        ->capture_default_str()
        ->group(sg);
    cmd.add_option("--speckle-range", d.speckle_range, "disparity step inside a speckle, px")
        ->capture_default_str()
        ->group(sg);
    cmd.add_option("--sgbm-mode", d.mode, "sgbm, hh, sgbm_3way or hh4")
        ->check(CLI::IsMember({"sgbm", "hh", "sgbm_3way", "hh4"}))
        ->capture_default_str()
        ->group(sg);
    cmd.add_flag("--colour-matching,!--grey-matching", d.colour, "match on RGB instead of grey")
        ->group(sg);
    cmd.add_flag("--pad-left,!--no-pad-left", d.pad_left,
                 "pad the views so the left border band (min + num disparities wide) is matched")
        ->group(sg);
    cmd.add_flag("--lr-check", d.lr_check, "drop pixels failing a full left-right check")
        ->group(sg);
    cmd.add_option("--lr-max-diff", d.lr_max_diff_px, "left-right tolerance, px")
        ->capture_default_str()
        ->group(sg);
    cmd.add_flag("--wls", d.wls, "WLS filtering (ximgproc): denser, smoother map")->group(sg);
    cmd.add_option("--downscale", d.downscale,
                   "match at 1/N resolution (1 or 2) and upsample the disparity")
        ->capture_default_str()
        ->group(sg);
    cmd.add_option("--wls-lambda", d.wls_lambda, "WLS smoothness")
        ->capture_default_str()
        ->group(sg);
    cmd.add_option("--wls-sigma", d.wls_sigma_colour, "WLS edge sensitivity")
        ->capture_default_str()
        ->group(sg);
    cmd.add_option("--matcher", d.matcher,
                   "sgbm (cv::StereoSGBM) or sgm (the project's census SGM: grey, 3 paths, "
                   "AVX2; uses the range, uniqueness, disp12, speckle and downscale flags)")
        ->check(CLI::IsMember({"sgbm", "sgm"}))
        ->capture_default_str()
        ->group(sg);
    cmd.add_option("--sgm-p1", d.sgm.p1, "sgm: penalty of +-1 px changes, census bits")
        ->capture_default_str()
        ->group(sg);
    cmd.add_option("--sgm-p2", d.sgm.p2, "sgm: penalty of larger changes, census bits")
        ->capture_default_str()
        ->group(sg);
    cmd.add_option("--sgm-subpixel", d.sgm.subpixel, "sgm: parabola or equiangular")
        ->check(CLI::IsMember({"parabola", "equiangular"}))
        ->capture_default_str()
        ->group(sg);
    cmd.add_flag("--sgm-median,!--no-sgm-median", d.sgm.median3,
                 "sgm: 3x3 median of the disparity before the speckle filter")
        ->group(sg);

    const std::string cl = "Cloud and entities";
    cmd.add_option("--max-range", a.options.reproject.max_range_m,
                   "drop points farther than this from the camera, m")
        ->capture_default_str()
        ->group(cl);
    cmd.add_flag("!--drop-void", a.options.reproject.keep_void,
                 "drop points whose semantic colour is not in the palette")
        ->group(cl);
    cmd.add_option("--method", a.method,
                   "entity extractor: instances, or the thesis's centroid, average, variance")
        ->check(CLI::IsMember({"instances", "centroid", "average", "variance"}))
        ->capture_default_str()
        ->group(cl);
    cmd.add_option("--class-config", a.class_config, "per-class settings JSON")->group(cl);
    cmd.add_flag("--fsync-clouds", a.fsync_clouds,
                 "also fsync the cloud files before renaming them (durable across a power loss; "
                 "about 1 ms per MB): without it they are written atomically but not fsync'ed")
        ->group(cl);
}

void add_output_flags(CLI::App& cmd, AnalyseArgs& a) {
    const std::string out = "Outputs (written only when every stage succeeded)";
    cmd.add_option("-o,--entities", a.entities, "entity JSON file ('-' = stdout)")->group(out);
    cmd.add_option("--xyz", a.xyz, "ASCII cloud for CloudCompare (//X Y Z R G B Class Luma)")
        ->group(out);
    cmd.add_option("--pcd", a.pcd, "binary PCD v0.7 cloud for PCL (x y z rgb label)")->group(out);
    cmd.add_option("--ply", a.ply, "binary PLY cloud (x y z, red green blue, scalar_class)")
        ->group(out);
    cmd.add_option("--disparity-png", a.disparity_png, "8-bit viewable disparity PNG")->group(out);
    cmd.add_option("--disparity-kitti", a.disparity_kitti,
                   "KITTI 16-bit disparity PNG (d*256, 0 = none)")
        ->group(out);
    cmd.add_option("--semantic-out", a.semantic_out,
                   "PNG of the per-pixel classes used, in the palette's colours (with "
                   "--semantics geometry: what the geometry decided)")
        ->group(out);
    cmd.add_option("--gt-disparity", a.gt_disparity,
                   "KITTI GT disparity PNG: print D1-all, EPE and density to stderr")
        ->group(out);
    cmd.add_flag("--timings", a.timings, "milliseconds per stage to stderr")->group(out);
}

void resolve_settings(AnalyseArgs& a, const CLI::App& cmd) {
    if (a.preset != "tuned") {
        // Start from the preset's values, then re-apply only flags the user gave.
        const auto preset = cloud_analysis::disparity_preset(a.preset);
        auto& d = a.options.disparity;
        const auto keep = [&](const char* flag, auto& field, const auto& value) {
            if (cmd.count(flag) == 0) field = value;
        };
        keep("--min-disparity", d.min_disparity, preset.min_disparity);
        keep("--num-disparities", d.num_disparities, preset.num_disparities);
        keep("--block-size", d.block_size, preset.block_size);
        keep("--p1", d.p1, preset.p1);
        keep("--p2", d.p2, preset.p2);
        keep("--disp12-max-diff", d.disp12_max_diff, preset.disp12_max_diff);
        keep("--pre-filter-cap", d.pre_filter_cap, preset.pre_filter_cap);
        keep("--uniqueness-ratio", d.uniqueness_ratio, preset.uniqueness_ratio);
        keep("--speckle-window-size", d.speckle_window_size, preset.speckle_window_size);
        keep("--speckle-range", d.speckle_range, preset.speckle_range);
        keep("--sgbm-mode", d.mode, preset.mode);
        keep("--lr-check", d.lr_check, preset.lr_check);
        keep("--wls", d.wls, preset.wls);
        keep("--downscale", d.downscale, preset.downscale);
        if (cmd.count("--colour-matching") == 0 && cmd.count("--grey-matching") == 0) {
            d.colour = preset.colour;
        }
        if (cmd.count("--pad-left") == 0 && cmd.count("--no-pad-left") == 0) {
            d.pad_left = preset.pad_left;
        }
    }
    try {
        a.options.validate();
    } catch (const std::invalid_argument& e) {
        throw CLI::ValidationError("analyse", e.what());
    }
}

void resolve(AnalyseArgs& a, const CLI::App& cmd) {
    if (!a.kitti_root.empty()) {
        if (a.frame.empty()) throw CLI::ValidationError("--kitti-root", "needs --frame");
        const auto k = cloud_analysis::kitti_layout(a.kitti_root, a.frame);
        if (a.paths.left.empty()) a.paths.left = k.left;
        if (a.paths.right.empty()) a.paths.right = k.right;
        if (a.paths.semantic.empty()) a.paths.semantic = k.semantic;
        if (a.paths.calibration.empty()) a.paths.calibration = k.calibration;
    }
    if (a.paths.left.empty()) throw CLI::RequiredError("--left (or --kitti-root and --frame)");
    if (a.paths.right.empty()) throw CLI::RequiredError("--right (or --kitti-root and --frame)");
    if (a.paths.calibration.empty()) {
        throw CLI::RequiredError("--calib (or --kitti-root and --frame)");
    }
    a.paths.frame_id = !a.frame.empty() ? a.frame : a.paths.left.stem().string();
    resolve_settings(a, cmd);
}

stereoscene::support::FileSync cloud_sync(const AnalyseArgs& a) {
    return a.fsync_clouds ? stereoscene::support::FileSync::kDurable
                          : stereoscene::support::FileSync::kAtomicOnly;
}

void write_output(const PendingOutput& out) {
    if (out.path == "-") {
        // SIGPIPE is ignored (main): a reader that went away is an error line, not a signal.
        if (std::fwrite(out.bytes.data(), 1, out.bytes.size(), stdout) != out.bytes.size() ||
            std::fflush(stdout) != 0) {
            throw std::runtime_error(std::string("cannot write output: standard output: ") +
                                     std::strerror(errno) + " (-)");
        }
    } else {
        stereoscene::support::write_file_atomic(out.path, out.bytes, out.sync);
    }
}

cloud_analysis::ExtractOptions extract_options(const AnalyseArgs& a) {
    cloud_analysis::ExtractOptions extract;
    extract.method = a.method;
    extract.classes = cloud_analysis::load_class_config(
        a.class_config.empty() ? cloud_analysis::default_class_config_path() : a.class_config);
    extract.validate();
    return extract;
}

std::string entity_json(const cloud_analysis::LoadedInputs& in,
                        const cloud_analysis::AnalyseResult& r, const AnalyseArgs& a,
                        const cloud_analysis::ExtractOptions& extract) {
    scene_schema::EntityDocument doc =
        r.points.xyz_m.empty()
            ? cloud_analysis::extract_entities(r.cloud, in.palette, r.camera, extract)
            : cloud_analysis::extract_entities(r.points, in.palette, extract);
    doc.frame.id = in.paths.frame_id;
    if (r.geometry) {
        // Classes from geometry are guesses the labelled path does not make: less confidence.
        for (auto& e : doc.entities) e.confidence *= cloud_analysis::geometry::kConfidenceScale;
        const auto& g = r.geometry->ground;
        doc.extra["stereo_ground"] = {{"found", g.found},
                                      {"camera_height_m", g.camera_height_m},
                                      {"pitch_deg", g.pitch_deg},
                                      {"roll_deg", g.roll_deg},
                                      {"horizon_v_px", g.horizon_v_px},
                                      {"problem", g.problem}};
    }
    scene_schema::CameraIntrinsics cam;
    cam.width_px = r.camera.width_px;
    cam.height_px = r.camera.height_px;
    cam.fx_px = r.camera.fx_px;
    cam.fy_px = r.camera.fy_px;
    cam.cx_px = r.camera.cx_px;
    cam.cy_px = r.camera.cy_px;
    cam.baseline_m = r.camera.baseline_m;
    doc.frame.camera = cam;
    nlohmann::json source = cloud_analysis::describe_run(in, a.options, STEREOSCENE_VERSION);
    source["extract"] = {{"method", a.method},
                         {"class_config", a.class_config.empty() ? std::string("default")
                                                                 : a.class_config.string()}};
    doc.source = source;
    return scene_schema::dump_checked(doc);
}

cloud_analysis::AnalyseOptions options_for_outputs(const AnalyseArgs& a,
                                                   const cloud_analysis::ExtractOptions& extract,
                                                   const cloud_analysis::Palette& palette,
                                                   bool clouds) {
    cloud_analysis::AnalyseOptions options = a.options;
    if (!clouds) options.class_points_only = cloud_analysis::class_selection(palette, extract);
    return options;
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
        {a.semantic_out.string(), "--semantic-out"}};
    int to_stdout = 0;
    for (const auto& [path, flag] : all_outputs) {
        if (path.empty()) continue;
        if (path == "-") {
            if (++to_stdout > 1) {
                throw CLI::ValidationError(flag, "only one output can go to stdout ('-')");
            }
            continue;
        }
        const std::filesystem::path folder = std::filesystem::path(path).parent_path();
        if (!folder.empty() && !std::filesystem::is_directory(folder)) {
            throw std::runtime_error("cannot write output: no such folder (" + folder.string() +
                                     ", " + flag + ")");
        }
    }
    LoadedRun run{{}, extract_options(a), std::nullopt};
    run.inputs = cloud_analysis::load_inputs(a.paths, a.options);
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

RunReport analyse_loaded_and_write(const LoadedRun& run, const AnalyseArgs& a,
                                   cloud_analysis::DisparityMatcher& matcher) {
    using Clock = std::chrono::steady_clock;
    const auto ms_since = [](Clock::time_point t) {
        return std::chrono::duration<double, std::milli>(Clock::now() - t).count();
    };
    const cloud_analysis::LoadedInputs& in = run.inputs;
    std::vector<cloud_analysis::StageTiming> timings;
    if (a.warnings && !in.calibration.note.empty()) {
        std::cerr << kTool << ": warning: " << in.calibration.note << " (" << in.calibration.source
                  << ")\n";
    }

    const bool any_cloud = !a.xyz.empty() || !a.pcd.empty() || !a.ply.empty();
    cloud_analysis::AnalyseResult r = cloud_analysis::analyse(
        in, options_for_outputs(a, run.extract, in.palette, any_cloud), matcher);
    timings.insert(timings.end(), r.timings.begin(), r.timings.end());
    if (a.warnings && r.geometry) {
        for (const auto& w : r.geometry->warnings) std::cerr << kTool << ": warning: " << w << "\n";
    }
    if (a.warnings && r.semantics == "none") {
        std::cerr << kTool << ": warning: no semantic image: every point is void\n";
    } else if (a.warnings && r.semantics == "labels" && r.classes.void_pixels > 0) {
        std::cerr << kTool << ": warning: " << r.classes.void_pixels
                  << " semantic pixels have colours not in palette '" << in.palette.name
                  << "' and count as void (" << a.paths.semantic.string() << ")\n";
    }
    if (run.gt_disparity) {
        const auto s = cloud_analysis::score_disparity(r.disparity, *run.gt_disparity);
        std::fprintf(stderr,
                     "%s: disparity vs %s: D1-all %.2f %%, D1-valid %.2f %%, EPE %.3f px, "
                     "density %.2f %% (%zu GT px)\n",
                     kTool, a.gt_disparity.string().c_str(), 100.0 * s.d1_all, 100.0 * s.d1_valid,
                     s.epe_px, 100.0 * s.density, s.gt_pixels);
    }

    std::vector<PendingOutput> outputs;
    auto t = Clock::now();
    if (!a.entities.empty()) {
        outputs.push_back({a.entities, entity_json(in, r, a, run.extract), "--entities"});
        timings.push_back({"entities", ms_since(t)});
    }
    const std::vector<std::pair<std::filesystem::path, const char*>> clouds = {
        {a.xyz, "--xyz"}, {a.pcd, "--pcd"}, {a.ply, "--ply"}};
    for (const auto& [path, flag] : clouds) {
        if (path.empty()) continue;
        t = Clock::now();
        outputs.push_back({path.string(),
                           cloud_analysis::format_cloud(
                               r.cloud, in.palette, cloud_analysis::cloud_format_from_path(path)),
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
        cloud_analysis::ClassImage classes = r.classes;
        if (classes.class_index.empty()) {  // no semantic image: every pixel void
            classes.width_px = r.camera.width_px;
            classes.height_px = r.camera.height_px;
            classes.class_index.assign(
                static_cast<std::size_t>(classes.width_px) * classes.height_px,
                cloud_analysis::kVoidClass);
        }
        outputs.push_back({a.semantic_out.string(),
                           cloud_analysis::encode_png(
                               cloud_analysis::geometry::colour_classes(classes, in.palette)),
                           "--semantic-out"});
        timings.push_back({"encode semantic", ms_since(t)});
    }
    // Every output exists in memory now: only writing is left.
    std::vector<std::filesystem::path> written;
    try {
        for (const auto& out : outputs) {
            t = Clock::now();
            write_output(out);
            if (out.path != "-") written.emplace_back(out.path);
            timings.push_back({"write " + out.label, ms_since(t)});
        }
    } catch (...) {
        // All or nothing: take back the files this run already wrote.
        std::error_code ignored;
        for (const auto& path : written) std::filesystem::remove(path, ignored);
        throw;
    }

    return {timings, r.cloud_points};
}

RunReport analyse_and_write(const AnalyseArgs& a, cloud_analysis::DisparityMatcher& matcher) {
    const auto start = std::chrono::steady_clock::now();
    const LoadedRun run = load_run(a);
    const double load_ms =
        std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
    RunReport report = analyse_loaded_and_write(run, a, matcher);
    report.timings.insert(report.timings.begin(), {"load", load_ms});
    return report;
}

RunReport analyse_and_write(const AnalyseArgs& a) {
    cloud_analysis::DisparityMatcher matcher(a.options.disparity);
    return analyse_and_write(a, matcher);
}

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
