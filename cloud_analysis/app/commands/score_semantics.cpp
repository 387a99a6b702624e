#include "score_semantics.hpp"

#include <cstdio>
#include <iostream>

#include <nlohmann/json.hpp>

#include "cloud_analysis/cloud/semantic.hpp"
#include "cloud_analysis/geometry/scene_geometry.hpp"
#include "cloud_analysis/io/io.hpp"
#include "output.hpp"

namespace cloud_analysis::app {

CLI::App* add_score_semantics_command(CLI::App& app, ScoreSemanticsArgs& a) {
    CLI::App* cmd = app.add_subcommand(
        "score-semantics",
        "a semantic image (e.g. --semantic-out) against the ground truth: pixel accuracy over "
        "the truth's non-void pixels and IoU per class");
    cmd->add_option("--estimate", a.estimate, "semantic colour PNG to score")->required();
    cmd->add_option("--truth", a.truth, "ground-truth semantic colour PNG, same size")->required();
    cmd->add_option("--palette", a.palette, "palette of both images")->capture_default_str();
    cmd->add_option("--classes", a.classes, "classes whose IoU is reported")->capture_default_str();
    cmd->add_option("--json", a.json, "also write the scores as JSON ('-' = stdout)");
    return cmd;
}

int run_score_semantics(const ScoreSemanticsArgs& a) {
    const Palette palette = load_palette(a.palette);
    const ClassImage estimate =
        classify_pixels(read_image(a.estimate, ImageMode::kColour), palette);
    const ClassImage truth = classify_pixels(read_image(a.truth, ImageMode::kColour), palette);
    if (estimate.width_px != truth.width_px || estimate.height_px != truth.height_px) {
        throw std::runtime_error(
            "inputs do not match: the estimate and the truth differ in size (" +
            a.estimate.string() + ")");
    }
    const geometry::SemanticScore s =
        geometry::score_semantics(estimate, truth, palette, a.classes);
    std::fprintf(stderr, "%s: semantics %s vs %s: pixel accuracy %.3f over %zu px\n", kTool,
                 a.estimate.string().c_str(), a.truth.string().c_str(), s.accuracy, s.pixels);
    nlohmann::json iou = nlohmann::json::object();
    for (const auto& [name, value] : s.iou) {
        std::fprintf(stderr, "  IoU %-12s %s\n", name.c_str(),
                     value < 0.0 ? "-" : std::to_string(value).substr(0, 5).c_str());
        iou[name] = value < 0.0 ? nlohmann::json(nullptr) : nlohmann::json(value);
    }
    if (!a.json.empty()) {
        const nlohmann::json j = {{"pixels", s.pixels}, {"accuracy", s.accuracy}, {"iou", iou}};
        write_output({a.json, j.dump(2) + "\n", "--json"});
    }
    return 0;
}

}  // namespace cloud_analysis::app
