#include <cmath>
#include <cstdio>
#include <sstream>

#include "cloud_analysis/evaluation/report.hpp"
#include "stereoscene/support/number_text.hpp"

namespace cloud_analysis {
namespace {

using stereoscene::support::fixed_text;

nlohmann::json box_json(const Eigen::Vector4d& b) {
    return {std::round(b[0] * 10) / 10, std::round(b[1] * 10) / 10, std::round(b[2] * 10) / 10,
            std::round(b[3] * 10) / 10};
}

std::string box_text(const Eigen::Vector4d& b) {
    return "[" + fixed_text(b[0], 0) + " " + fixed_text(b[1], 0) + " " + fixed_text(b[2], 0) + " " +
           fixed_text(b[3], 0) + "]";
}

nlohmann::json counts_json(const Counts2d& c, std::size_t frames) {
    return {{"owed", c.owed},
            {"found", c.found},
            {"recall", c.recall()},
            {"counted", c.counted},
            {"correct", c.correct},
            {"false", c.false_entities()},
            {"precision", c.precision()},
            {"false_per_frame", frames == 0 ? 0.0 : double(c.false_entities()) / double(frames)},
            {"ignored", c.ignored}};
}

/// One frame's false entities and missed labels, as JSON and table lines.
nlohmann::json frame_detail(const Labels2dComparison& c, std::size_t f, std::ostringstream& table) {
    const FrameScore2d& score = c.scores[f];
    nlohmann::json falses = nlohmann::json::array(), missed = nlohmann::json::array();
    for (const auto& s : score.entities) {
        if (s.outcome != Scored2d::Outcome::false_entity) continue;
        const auto& e = c.estimate[f][s.entity];
        falses.push_back({{"id", e.id},
                          {"class", e.class_name},
                          {"range_m", std::round(s.range_m * 100) / 100},
                          {"box_px", box_json(s.box_px)}});
        table << "  " << score.frame << "  false   " << e.id << " at " << fixed_text(s.range_m, 1)
              << " m, box " << box_text(s.box_px) << "\n";
    }
    for (const auto l : score.missed) {
        const Label2d& label = c.labels[f].objects[l];
        missed.push_back(
            {{"type", label.type}, {"track", label.track}, {"box_px", box_json(label.box_px)}});
        table << "  " << score.frame << "  missed  " << label.type
              << (label.track.empty() ? "" : " " + label.track) << ", box "
              << box_text(label.box_px) << "\n";
    }
    nlohmann::json j = {{"frame", score.frame}, {"false", falses}, {"missed", missed}};
    for (int k = 0; k < kCategory2dCount; ++k) {
        j[std::string(category_name(static_cast<Category2d>(k)))] = counts_json(score.counts[k], 1);
    }
    return j;
}

}  // namespace

void report_labels_2d(const Labels2dComparison& c, const Match2dOptions& options,
                      const Labels2dBars& bars, EvaluationReport& report) {
    const std::size_t frames = c.scores.size();
    Counts2d total[kCategory2dCount];
    for (const auto& s : c.scores)
        for (int k = 0; k < kCategory2dCount; ++k) total[k] += s.counts[k];

    std::ostringstream table;
    table << "2D labels " << c.labels_file << " against " << c.entities_source
          << (c.tracked_only ? " (confirmed tracks only)" : "") << ": " << frames
          << (frames == 1 ? " frame" : " frames") << " (labels owed from "
          << fixed_text(options.min_height_px, 0) << " px tall, entities counted within "
          << fixed_text(options.max_range_m, 0) << " m)\n";
    table << "  category  owed found recall  counted correct precision false/frame\n";
    nlohmann::json categories = nlohmann::json::object();
    for (int k = 0; k < kCategory2dCount; ++k) {
        const Counts2d& t = total[k];
        const std::string name(category_name(static_cast<Category2d>(k)));
        categories[name] = counts_json(t, frames);
        char line[160];
        std::snprintf(line, sizeof line, "  %-8s %5zu %5zu %6.3f %8zu %7zu %9.3f %11.2f\n",
                      name.c_str(), t.owed, t.found, t.recall(), t.counted, t.correct,
                      t.precision(), frames == 0 ? 0.0 : double(t.false_entities()) / frames);
        table << line;
    }
    nlohmann::json per_frame = nlohmann::json::array();
    for (std::size_t f = 0; f < frames; ++f) per_frame.push_back(frame_detail(c, f, table));

    const Counts2d& b = total[static_cast<int>(bars.category)];
    const double false_per_frame = frames == 0 ? 0.0 : double(b.false_entities()) / frames;
    const std::string cat(category_name(bars.category));
    if (bars.require_recall >= 0.0 && b.recall() < bars.require_recall) {
        report.missed_bars.push_back(cat + " recall " + fixed_text(b.recall(), 3) + " < " +
                                     fixed_text(bars.require_recall, 3) + " (--require-recall)");
    }
    if (bars.max_false_per_frame >= 0.0 && false_per_frame > bars.max_false_per_frame) {
        report.missed_bars.push_back(cat + " false per frame " + fixed_text(false_per_frame, 2) +
                                     " > " + fixed_text(bars.max_false_per_frame, 2) +
                                     " (--max-false-per-frame)");
    }
    report.table += table.str();
    report.json["labels_2d"] = {{"labels_file", c.labels_file},
                                {"entities", c.entities_source},
                                {"tracked_only", c.tracked_only},
                                {"frames", frames},
                                {"min_iou", options.min_iou},
                                {"hidden_min_cover", options.hidden_min_cover},
                                {"hidden_min_iou", options.hidden_min_iou},
                                {"min_height_px", options.min_height_px},
                                {"max_occluded", options.max_occluded},
                                {"max_truncated", options.max_truncated},
                                {"max_range_m", options.max_range_m},
                                {"categories", categories},
                                {"per_frame", per_frame}};
}

}  // namespace cloud_analysis
