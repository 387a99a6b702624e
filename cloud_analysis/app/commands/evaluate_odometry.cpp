#include "evaluate_odometry.hpp"

#include <iostream>

#include <stereoscene/support/file_read.hpp>
#include <stereoscene/support/number_text.hpp>

#include "cloud_analysis/evaluation/odometry_eval.hpp"
#include "output.hpp"

namespace cloud_analysis::app {

namespace {

using stereoscene::support::fixed_text;

std::vector<odometry::Pose> read_poses(const std::filesystem::path& path, const char* flag) {
    std::string text;
    try {
        text = stereoscene::support::read_text_input(path);
    } catch (const stereoscene::support::FileError& e) {
        throw std::runtime_error("cannot read poses: " + e.reason() + " (" + path.string() + ", " +
                                 flag + ")");
    }
    return odometry::parse_kitti_poses(text, path.string());
}

}  // namespace

CLI::App* add_evaluate_odometry_command(CLI::App& app, EvaluateOdometryArgs& a) {
    CLI::App* cmd = app.add_subcommand(
        "evaluate-odometry",
        "score a drive's poses against the truth: KITTI's translation error (% of the segment "
        "length) and rotation error (deg/m) over the segment lengths the drive has, and the end "
        "point's error (see docs/odometry.md)");
    cmd->add_option("--poses", a.poses, "estimated poses, KITTI odometry text (batch --odometry)")
        ->required();
    cmd->add_option("--truth", a.truth, "true poses of the same frames, KITTI odometry text")
        ->required();
    cmd->add_option("--json", a.json, "also write the scores as JSON ('-' = stdout)");
    const std::string bg = "Bars (exit 3 when one is missed; off unless given)";
    cmd->add_option("--max-translation-error", a.max_translation_pct,
                    "largest mean translation error, % of the segment length")
        ->check(CLI::NonNegativeNumber)
        ->group(bg);
    cmd->add_option("--max-rotation-error", a.max_rotation_deg_per_m,
                    "largest mean rotation error, degrees a metre")
        ->check(CLI::NonNegativeNumber)
        ->group(bg);
    cmd->add_option("--max-end-point-error", a.max_end_point_pct,
                    "largest end point error, % of the path")
        ->check(CLI::NonNegativeNumber)
        ->group(bg);
    return cmd;
}

int run_evaluate_odometry(const EvaluateOdometryArgs& a) {
    const std::vector<odometry::Pose> estimate = read_poses(a.poses, "--poses");
    const std::vector<odometry::Pose> truth = read_poses(a.truth, "--truth");
    OdometryErrors e;
    try {
        e = evaluate_odometry(estimate, truth);
    } catch (const std::invalid_argument& err) {
        throw std::runtime_error(std::string("cannot score odometry: ") + err.what() + " (" +
                                 a.poses.string() + ")");
    }
    if (!a.json.empty()) write_output({a.json, e.to_json().dump(2) + "\n", "--json"});
    if (a.json != "-") {
        std::cout << "odometry over " << e.frames << " frames, " << fixed_text(e.path_m, 1)
                  << " m of true path\n";
        std::cout << "  length_m  segments  translation_%  rotation_deg/m\n";
        for (const auto& s : e.lengths) {
            std::printf("  %8.0f  %8zu  %13.2f  %14.4f\n", s.length_m, s.segments,
                        s.translation_pct, s.rotation_deg_per_m);
        }
        std::cout << "  mean translation error " << fixed_text(e.translation_pct, 2)
                  << " %, rotation error " << fixed_text(e.rotation_deg_per_m, 4) << " deg/m\n";
        std::cout << "  end point error " << fixed_text(e.end_point_m, 2)
                  << " m = " << fixed_text(e.end_point_pct, 2) << " % of the path\n";
        std::cout.flush();
    }
    int code = 0;
    if (a.max_translation_pct && !(e.translation_pct <= *a.max_translation_pct)) {
        std::cerr << kTool << ": bar missed: translation error " << fixed_text(e.translation_pct, 2)
                  << " % > " << *a.max_translation_pct << " (--max-translation-error)\n";
        code = 3;
    }
    if (a.max_rotation_deg_per_m && !(e.rotation_deg_per_m <= *a.max_rotation_deg_per_m)) {
        std::cerr << kTool << ": bar missed: rotation error " << fixed_text(e.rotation_deg_per_m, 4)
                  << " deg/m > " << *a.max_rotation_deg_per_m << " (--max-rotation-error)\n";
        code = 3;
    }
    if (a.max_end_point_pct && !(e.end_point_pct <= *a.max_end_point_pct)) {
        std::cerr << kTool << ": bar missed: end point error " << fixed_text(e.end_point_pct, 2)
                  << " % > " << *a.max_end_point_pct << " (--max-end-point-error)\n";
        code = 3;
    }
    return code;
}

}  // namespace cloud_analysis::app
