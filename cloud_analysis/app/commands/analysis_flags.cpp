#include "analysis_flags.hpp"

#include <algorithm>
#include <stdexcept>
#include <string>

#include "cloud_analysis/cloud/cloud_io.hpp"
#include "cloud_analysis/cloud/semantic.hpp"
#include "cloud_analysis/entities/class_config.hpp"
#include "cloud_analysis/geometry/segment_classifier.hpp"
#include "cloud_analysis/io/io.hpp"
#include "cloud_analysis/stereo/calibration.hpp"
#include "cloud_analysis/stereo/disparity.hpp"

namespace cloud_analysis::app {

void add_input_flags(CLI::App& cmd, AnalyseArgs& a) {
    const std::string in = "Inputs";
    cmd.add_option("--left,-l", a.paths.left, "left rectified image (PNG/JPG)")->group(in);
    cmd.add_option("--right,-r", a.paths.right, "right rectified image")->group(in);
    cmd.add_option("--semantic,-s", a.paths.semantic, "semantic colour image of the left view")
        ->group(in);
    cmd.add_option("--instance", a.paths.instance,
                   "instance image of the left view (16-bit KITTI or Cityscapes ids, or 8-bit RGB "
                   "colours): each object taken whole, needs --semantic")
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
    cmd.add_flag("--instances", a.kitti_instances,
                 "--kitti-root: also read its instance/<frame>.png (see --instance)")
        ->group(in);
}

namespace {

/// Settings of the inputs: raw images, KITTI camera indices, palette.
void add_input_settings_flags(CLI::App& cmd, AnalyseArgs& a) {
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
    cmd.add_option("--disparity-offset", a.options.calibration.disparity_offset_px,
                   "the rig's disparity offset, px: added to every matched disparity before "
                   "depth (batch --odometry estimates it from a drive; docs/clouds.md)")
        ->check(CLI::Range(-kMaxDisparityOffsetPx, kMaxDisparityOffsetPx))
        ->capture_default_str()
        ->group(in);
    cmd.add_option("--semantics", a.options.semantics,
                   "classes from: labels (the semantic image), geometry (the stereo pair alone, "
                   "docs/stereo-only.md) or auto (labels when a semantic image is given)")
        ->check(CLI::IsMember({"labels", "geometry", "auto"}))
        ->capture_default_str()
        ->group(in);
    cmd.add_option("--instance-encoding", a.options.instance_encoding,
                   "how the instance image stores objects: auto (16-bit: KITTI or Cityscapes, "
                   "whichever matches the semantic image; 8-bit: colours), kitti (labelId << 8 | "
                   "n), cityscapes (labelId * 1000 + n) or colour (RGB, black = none)")
        ->check(CLI::IsMember({"auto", "kitti", "cityscapes", "colour"}))
        ->capture_default_str()
        ->group(in);
    cmd.add_option("--stereo-segmentation", a.options.geometry.segmentation,
                   "--semantics geometry: obstacles split by columns (u-disparity, the default) "
                   "or clusters (3D Euclidean clustering; docs/entities.md compares them)")
        ->check(CLI::IsMember({"columns", "clusters"}))
        ->capture_default_str()
        ->group(in);
    cmd.add_option("--vehicle-classifier", a.vehicle_classifier,
                   "--semantics geometry: the random trees that decide which segments are "
                   "vehicles (a cv::ml::RTrees file), default (the project's, trained on "
                   "rendered streets; docs/stereo-only.md) or none (the rules decide)")
        ->capture_default_str()
        ->group(in);
    cmd.add_option("--person-classifier", a.person_classifier,
                   "--semantics geometry: the random trees that decide which segments that are "
                   "no vehicle are persons (a cv::ml::RTrees file), default (the project's, "
                   "trained on rendered streets; docs/stereo-only.md) or none (the rules decide)")
        ->capture_default_str()
        ->group(in);
    cmd.add_option("--palette", a.options.palette,
                   "semantic palette: cityscapes, carla, thesis or a palette JSON file")
        ->capture_default_str()
        ->group(in);
}

/// How the disparity range and the pixel settings follow the rig (pipeline/rig_fit.hpp).
void add_rig_flags(CLI::App& cmd, AnalyseArgs& a, const std::string& sg) {
    auto& rig = a.options.rig;
    cmd.add_option("--min-depth", rig.min_depth_m,
                   "nearest depth to match, metres: sets --num-disparities from the rig "
                   "(fx B / depth, to a multiple of 16); 0 = --num-disparities (128)")
        ->capture_default_str()
        ->group(sg);
    cmd.add_option("--half-resolution-above", rig.half_resolution_above_px,
                   "frames with more pixels are analysed at half resolution; 0 = never")
        ->capture_default_str()
        ->group(sg);
    cmd.add_flag("--no-rig-scaling", a.no_rig_scaling,
                 "keep every pixel setting as written for KITTI's focal length (721.5 px) "
                 "instead of scaling it to the rig's")
        ->group(sg);
    cmd.add_option("--point-lattice", a.point_lattice,
                   "things are taken on every N-th pixel of every N-th row (1, 2, 4 or 8); 0 = "
                   "from the rig: the largest power of two up to fx / 721.5 (docs/cli.md)")
        ->check(CLI::IsMember({0, 1, 2, 4, 8}))
        ->capture_default_str()
        ->group(sg);
}

/// The matcher's post-filters: left-right check, WLS, half-resolution matching.
void add_post_filter_flags(CLI::App& cmd, DisparityOptions& d, const std::string& sg) {
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
}

/// Settings of the matcher: preset and cv::StereoSGBM parameters, post-filters.
void add_disparity_flags(CLI::App& cmd, AnalyseArgs& a) {
    auto& d = a.options.disparity;
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
    cmd.add_option("--num-disparities", d.num_disparities,
                   "search range, px, multiple of 16 (default: from --min-depth and the rig)")
        ->group(sg);
    add_rig_flags(cmd, a, sg);
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
    add_post_filter_flags(cmd, d, sg);
}

/// The choice of matcher and the settings of the project's own SGM.
void add_matcher_flags(CLI::App& cmd, AnalyseArgs& a) {
    auto& d = a.options.disparity;
    const std::string sg = "Disparity (cv::StereoSGBM)";
    cmd.add_option("--matcher", d.matcher,
                   "sgbm (cv::StereoSGBM) or sgm (the project's census SGM: grey, 3 paths, "
                   "AVX2; uses the range, uniqueness, disp12, speckle and downscale flags)")
        ->check(CLI::IsMember({"sgbm", "sgm"}))
        ->capture_default_str()
        ->group(sg);
    cmd.add_option("--sgm-window", d.sgm.window,
                   "sgm: side of the box the census costs are summed over, px, odd")
        ->capture_default_str()
        ->group(sg);
    cmd.add_option("--sgm-intensity-cap", d.sgm.intensity_cap,
                   "sgm: adds min(|I_left - I_right|, cap) to the census cost, grey levels; "
                   "0 = census alone")
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
}

/// Settings of the cloud and the entity extractor.
void add_cloud_flags(CLI::App& cmd, AnalyseArgs& a) {
    const std::string cl = "Cloud and entities";
    cmd.add_option("--max-range", a.options.reproject.max_range_m,
                   "drop points farther than this from the camera, m")
        ->capture_default_str()
        ->group(cl);
    cmd.add_option("--depth-edge-step", a.options.reproject.depth_edge_step_m,
                   "a thing's points with a point this much nearer within 4 rows above or below "
                   "(a depth step, where the disparity mixes two surfaces) do not shape its box, "
                   "m; 0 = off (docs/entities.md)")
        ->capture_default_str()
        ->group(cl);
    cmd.add_flag("!--drop-void", a.options.reproject.keep_void,
                 "drop points whose semantic colour is not in the palette")
        ->group(cl);
    cmd.add_option("--drop-classes", a.drop_classes,
                   "classes left out of the cloud files (e.g. sky vegetation; void = points "
                   "without a class); entities are not affected")
        ->delimiter(',')
        ->group(cl);
    cmd.add_flag("--drop-sky", a.drop_sky,
                 "leave the sky out of the cloud files (its points at 40-70 m stand as a wall "
                 "in cloud viewers); the same as --drop-classes sky")
        ->group(cl);
    cmd.add_option("--method", a.method,
                   "entity extractor: instances, or the thesis's centroid, average, variance")
        ->check(CLI::IsMember({"instances", "centroid", "average", "variance"}))
        ->capture_default_str()
        ->group(cl);
    cmd.add_option("--row-model", a.row_model,
                   "how rows of parked things are cut: partition (one optimisation over the row; "
                   "docs/entities.md) or rules (the older cascade: valleys, then walks of the "
                   "prior pitch)")
        ->check(CLI::IsMember({"rules", "partition"}))
        ->capture_default_str()
        ->group(cl);
    cmd.add_option("--class-config", a.class_config, "per-class settings JSON")->group(cl);
    cmd.add_flag("--fsync-clouds", a.fsync_clouds,
                 "also fsync the cloud files before renaming them (durable across a power loss; "
                 "about 1 ms per MB): without it they are written atomically but not fsync'ed")
        ->group(cl);
}

}  // namespace

void add_settings_flags(CLI::App& cmd, AnalyseArgs& a) {
    add_input_settings_flags(cmd, a);
    add_disparity_flags(cmd, a);
    add_matcher_flags(cmd, a);
    add_cloud_flags(cmd, a);
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
    cmd.add_option("--segments-out", a.segments_out,
                   "JSON of the stereo-only path's obstacle segments: each one's class, what the "
                   "rules measured of it and its image box (needs --semantics geometry or no "
                   "semantic image)")
        ->group(out);
    cmd.add_option("--segment-ids-out", a.segment_ids_out,
                   "16-bit PNG of the segments' pixels: index in --segments-out + 1, 0 = none "
                   "(the stereo-only path)")
        ->group(out);
    cmd.add_option("--gt-disparity", a.gt_disparity,
                   "KITTI GT disparity PNG: print D1-all, EPE and density to stderr")
        ->group(out);
    cmd.add_flag("--timings", a.timings, "milliseconds per stage to stderr")->group(out);
}

namespace {

/// An options field's validate() message "<field>: <reason>" as a usage error naming the flag
/// that sets the field ("min_disparity" -> --min-disparity) when the command has that flag.
CLI::ValidationError flag_error(const CLI::App& cmd, const std::string& message) {
    const std::size_t colon = message.find(": ");
    if (colon != std::string::npos) {
        std::string flag = "--" + message.substr(0, colon);
        std::replace(flag.begin(), flag.end(), '_', '-');
        if (cmd.get_option_no_throw(flag) != nullptr) {
            return CLI::ValidationError(flag, message.substr(colon + 2));
        }
    }
    return CLI::ValidationError(cmd.get_name(), message);
}

/// The classifier a --vehicle-classifier or --person-classifier value names: none, the
/// project's (default) or a manifest file; null for none.
std::shared_ptr<const cloud_analysis::geometry::SegmentClassifier> load_classifier(
    const std::string& flag, const std::string& value,
    cloud_analysis::geometry::SegmentTarget target) {
    using cloud_analysis::geometry::SegmentClassifier;
    if (value == "none") return nullptr;
    const std::filesystem::path file =
        value == "default" ? cloud_analysis::geometry::default_segment_classifier_path(target)
                           : std::filesystem::path(value);
    try {
        return SegmentClassifier::load(file, target);
    } catch (const std::runtime_error& e) {
        throw CLI::ValidationError(flag, e.what());
    }
}

}  // namespace

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
        keep("--sgm-window", d.sgm.window, preset.sgm.window);
        keep("--sgm-intensity-cap", d.sgm.intensity_cap, preset.sgm.intensity_cap);
        keep("--sgm-p1", d.sgm.p1, preset.sgm.p1);
        keep("--sgm-p2", d.sgm.p2, preset.sgm.p2);
        if (cmd.count("--colour-matching") == 0 && cmd.count("--grey-matching") == 0) {
            d.colour = preset.colour;
        }
        if (cmd.count("--pad-left") == 0 && cmd.count("--no-pad-left") == 0) {
            d.pad_left = preset.pad_left;
        }
    }
    // A range the user gave is kept as given when the analysis is fitted to the rig (the
    // scaled pixel settings have no flags).
    auto& rig = a.options.rig;
    rig.scale_pixel_settings = !a.no_rig_scaling;
    rig.given.clear();
    if (cmd.count("--num-disparities") > 0) rig.given.insert("num_disparities");
    if (a.point_lattice > 0) rig.given.insert("point_lattice_px");
    try {
        a.options.validate();
    } catch (const std::invalid_argument& e) {
        throw flag_error(cmd, e.what());
    }
    // The trees are read only when the stereo-only path may run: not for labels, nor for a
    // single frame given its semantic image.
    const bool geometry_may_run = a.options.semantics == "geometry" ||
                                  (a.options.semantics == "auto" && a.paths.semantic.empty());
    if (geometry_may_run) {
        using cloud_analysis::geometry::SegmentTarget;
        a.options.geometry.classifier =
            load_classifier("--vehicle-classifier", a.vehicle_classifier, SegmentTarget::vehicle);
        a.options.geometry.person_classifier =
            load_classifier("--person-classifier", a.person_classifier, SegmentTarget::person);
    }
    if (a.drop_sky) a.drop_classes.push_back("sky");
    if (!a.drop_classes.empty()) {
        try {
            cloud_analysis::class_indices(cloud_analysis::load_palette(a.options.palette),
                                          a.drop_classes);
        } catch (const std::invalid_argument& e) {
            throw CLI::ValidationError("--drop-classes", e.what());
        }
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
        if (a.kitti_instances && a.paths.instance.empty()) {
            a.paths.instance = cloud_analysis::kitti_instance_path(a.kitti_root, a.frame);
        }
    } else if (a.kitti_instances) {
        throw CLI::ValidationError("--instances", "needs --kitti-root (its instance/ folder)");
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

cloud_analysis::ExtractOptions extract_options(const AnalyseArgs& a) {
    cloud_analysis::ExtractOptions extract;
    extract.method = a.method;
    extract.row_model = a.row_model;
    if (a.point_lattice > 0) extract.point_lattice_px = a.point_lattice;
    extract.classes = cloud_analysis::load_class_config(
        a.class_config.empty() ? cloud_analysis::default_class_config_path() : a.class_config);
    extract.validate();
    return extract;
}

cloud_analysis::RunSettings run_settings(const AnalyseArgs& a) {
    return {a.options, a.class_config.empty() ? std::string("default") : a.class_config.string(),
            STEREOSCENE_VERSION, nullptr};
}

}  // namespace cloud_analysis::app
