#include "cloud_analysis/evaluation/entity_eval.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <map>
#include <set>
#include <stdexcept>

#include <nlohmann/json.hpp>

#include "cloud_analysis/io/io.hpp"
#include "cloud_analysis/support/box_axes.hpp"
#include "scene_schema/entities.hpp"
#include "scene_schema/json_text.hpp"
#include "stereoscene/support/angles.hpp"
#include "stereoscene/support/file_read.hpp"

namespace cloud_analysis {
namespace {

using Polygon = std::vector<Eigen::Vector2d>;

double cross(const Eigen::Vector2d& a, const Eigen::Vector2d& b) {
    return a.x() * b.y() - a.y() * b.x();
}

double polygon_area(const Polygon& p) {
    double twice = 0.0;
    for (std::size_t i = 0; i < p.size(); ++i) twice += cross(p[i], p[(i + 1) % p.size()]);
    return 0.5 * std::abs(twice);
}

Polygon footprint(const scene_schema::Entity& e) {
    const auto c = footprint_corners(e);
    return Polygon(c.begin(), c.end());
}

/// Share of a's footprint area inside b's footprint.
double inside_share(const scene_schema::Entity& a, const scene_schema::Entity& b) {
    const double area = a.W * a.L;
    return area > 0.0 ? convex_intersection_area(footprint(a), footprint(b)) / area : 0.0;
}

using stereoscene::support::kPi;
constexpr std::size_t kAll = kDistanceBinEdges_m.size();

std::string fmt(double v) {
    char buf[32];
    std::snprintf(buf, sizeof buf, "%.3f", v);
    return buf;
}

}  // namespace

std::array<Eigen::Vector2d, 4> footprint_corners(const scene_schema::Entity& box) {
    return BoxAxes(box.theta).corners(box.x, box.z, box.L, box.W);
}

double convex_intersection_area(const Polygon& a, const Polygon& b) {
    Polygon out = a;
    for (std::size_t i = 0; i < b.size() && !out.empty(); ++i) {
        const Eigen::Vector2d p = b[i];
        const Eigen::Vector2d q = b[(i + 1) % b.size()];
        const auto side = [&](const Eigen::Vector2d& v) { return cross(q - p, v - p); };
        Polygon in;
        in.swap(out);
        for (std::size_t k = 0; k < in.size(); ++k) {
            const Eigen::Vector2d s = in[k];
            const Eigen::Vector2d e = in[(k + 1) % in.size()];
            const double ds = side(s);
            const double de = side(e);
            if (ds >= 0.0) out.push_back(s);
            if ((ds >= 0.0) != (de >= 0.0)) out.push_back(s + (e - s) * (ds / (ds - de)));
        }
    }
    return out.size() < 3 ? 0.0 : polygon_area(out);
}

double bev_iou(const scene_schema::Entity& a, const scene_schema::Entity& b) {
    const double inter = convex_intersection_area(footprint(a), footprint(b));
    const double uni = a.W * a.L + b.W * b.L - inter;
    return uni > 0.0 ? std::clamp(inter / uni, 0.0, 1.0) : 0.0;
}

double iou_3d(const scene_schema::Entity& a, const scene_schema::Entity& b) {
    const double y_overlap = std::max(0.0, std::min(a.y + 0.5 * a.H, b.y + 0.5 * b.H) -
                                               std::max(a.y - 0.5 * a.H, b.y - 0.5 * b.H));
    const double inter = convex_intersection_area(footprint(a), footprint(b)) * y_overlap;
    const double uni = a.W * a.L * a.H + b.W * b.L * b.H - inter;
    return uni > 0.0 ? std::clamp(inter / uni, 0.0, 1.0) : 0.0;
}

double heading_error_rad(double theta_a, double theta_b) {
    const double d = std::fmod(std::abs(theta_a - theta_b), kPi);
    return std::min(d, kPi - d);
}

double bev_range_m(const scene_schema::Entity& box) { return std::hypot(box.x, box.z); }

int distance_bin(double range_m) {
    for (std::size_t i = 0; i < kDistanceBinEdges_m.size(); ++i) {
        if (range_m < kDistanceBinEdges_m[i]) return static_cast<int>(i);
    }
    return -1;
}

std::string distance_bin_name(int bin) {
    if (bin < 0 || bin > static_cast<int>(kAll)) throw std::out_of_range("distance bin");
    if (bin == static_cast<int>(kAll)) return "all";
    const double lo = bin == 0 ? 0.0 : kDistanceBinEdges_m[bin - 1];
    return std::to_string(static_cast<int>(lo)) + "-" +
           std::to_string(static_cast<int>(kDistanceBinEdges_m[bin]));
}

void EntityEvalOptions::validate() const {
    if (!(max_match_distance_m > 0.0)) {
        throw std::invalid_argument("max_match_distance_m: must be > 0");
    }
    if (!(max_range_m > 0.0)) throw std::invalid_argument("max_range_m: must be > 0");
    if (!(iou_threshold > 0.0 && iou_threshold <= 1.0)) {
        throw std::invalid_argument("iou_threshold: must be in (0, 1]");
    }
    if (!(stuff_overlap > 0.0 && stuff_overlap <= 1.0)) {
        throw std::invalid_argument("stuff_overlap: must be in (0, 1]");
    }
}

bool EntityEvalOptions::is_thing(const std::string& class_name) const {
    return std::find(thing_classes.begin(), thing_classes.end(), class_name) != thing_classes.end();
}

double ClassBinScore::recall() const {
    return reference == 0 ? 1.0 : static_cast<double>(matched) / static_cast<double>(reference);
}

double ClassBinScore::precision() const {
    const std::size_t n = matched + spurious;
    return n == 0 ? 1.0 : static_cast<double>(matched) / static_cast<double>(n);
}

double ClassBinScore::good_iou_fraction() const {
    return reference == 0 ? 1.0 : static_cast<double>(good_iou) / static_cast<double>(reference);
}

ClassBinScore EntityEvaluation::within(const std::string& class_name, double max_range_m) const {
    ClassBinScore sum;
    for (const auto& c : classes) {
        if (c.class_name != class_name) continue;
        for (std::size_t i = 0; i < kAll; ++i) {
            if (kDistanceBinEdges_m[i] > max_range_m + 1e-9) break;
            const ClassBinScore& b = c.bins[i];
            sum.reference += b.reference;
            sum.estimate += b.estimate;
            sum.matched += b.matched;
            sum.missed += b.missed;
            sum.spurious += b.spurious;
            sum.good_iou += b.good_iou;
            const auto append = [](auto& to, const auto& from) {
                to.insert(to.end(), from.begin(), from.end());
            };
            append(sum.centre_errors_m, b.centre_errors_m);
            append(sum.heading_errors_deg, b.heading_errors_deg);
            append(sum.bev_ious, b.bev_ious);
            append(sum.ious_3d, b.ious_3d);
            append(sum.size_errors_m, b.size_errors_m);
        }
    }
    return sum;
}

std::size_t EntityEvaluation::stuff_on_things(double max_range_m) const {
    std::size_t n = 0;
    for (const auto& c : classes) {
        if (!c.thing) n += within(c.class_name, max_range_m).spurious;
    }
    return n;
}

namespace {

bool in_range(const scene_schema::Entity& e, const EntityEvalOptions& options) {
    return bev_range_m(e) <= options.max_range_m && distance_bin(bev_range_m(e)) >= 0;
}

/// Pairs of the same thing class within the match distance, taken greedily by ascending centre
/// distance, one to one; marks the references and estimates used.
std::vector<EntityMatch> match_entities(const std::vector<scene_schema::Entity>& reference,
                                        const std::vector<scene_schema::Entity>& estimate,
                                        const EntityEvalOptions& options,
                                        std::vector<bool>& ref_used, std::vector<bool>& est_used) {
    std::vector<EntityMatch> matches;
    struct Candidate {
        double distance_m;
        std::size_t r, e;
    };
    std::vector<Candidate> candidates;
    for (std::size_t r = 0; r < reference.size(); ++r) {
        if (!options.is_thing(reference[r].class_name) || !in_range(reference[r], options))
            continue;
        for (std::size_t e = 0; e < estimate.size(); ++e) {
            if (estimate[e].class_name != reference[r].class_name ||
                !in_range(estimate[e], options)) {
                continue;
            }
            const double d =
                std::hypot(estimate[e].x - reference[r].x, estimate[e].z - reference[r].z);
            if (d <= options.max_match_distance_m) candidates.push_back({d, r, e});
        }
    }
    std::stable_sort(
        candidates.begin(), candidates.end(),
        [](const Candidate& a, const Candidate& b) { return a.distance_m < b.distance_m; });
    for (const auto& c : candidates) {
        if (ref_used[c.r] || est_used[c.e]) continue;
        ref_used[c.r] = est_used[c.e] = true;
        const auto& ref = reference[c.r];
        const auto& est = estimate[c.e];
        EntityMatch m;
        m.reference = c.r;
        m.estimate = c.e;
        m.centre_error_m =
            (Eigen::Vector3d(est.x, est.y, est.z) - Eigen::Vector3d(ref.x, ref.y, ref.z)).norm();
        m.bev_centre_error_m = c.distance_m;
        m.size_error_m = Eigen::Vector3d(est.W - ref.W, est.H - ref.H, est.L - ref.L);
        m.heading_error_rad = heading_error_rad(est.theta, ref.theta);
        m.bev_iou = bev_iou(ref, est);
        m.iou_3d = iou_3d(ref, est);
        matches.push_back(m);
    }
    return matches;
}

/// True when an unmatched estimate counts as spurious: a thing, or stuff lying at least
/// stuff_overlap inside a reference thing.
bool offends(const scene_schema::Entity& est, const std::vector<scene_schema::Entity>& reference,
             const EntityEvalOptions& options) {
    bool offends = options.is_thing(est.class_name);
    if (!offends) {
        for (const auto& ref : reference) {
            if (options.is_thing(ref.class_name) &&
                inside_share(est, ref) >= options.stuff_overlap) {
                offends = true;
                break;
            }
        }
    }
    return offends;
}

}  // namespace

EntityEvaluation evaluate_entities(const std::vector<scene_schema::Entity>& reference,
                                   const std::vector<scene_schema::Entity>& estimate,
                                   const EntityEvalOptions& options,
                                   const std::vector<bool>& reference_ignored) {
    options.validate();
    if (!reference_ignored.empty() && reference_ignored.size() != reference.size()) {
        throw std::invalid_argument("reference_ignored: size differs from the reference list");
    }
    const auto ignored = [&](std::size_t r) {
        return !reference_ignored.empty() && reference_ignored[r];
    };
    EntityEvaluation ev;
    ev.options = options;
    std::map<std::string, ClassScore> classes;
    const auto score_of = [&](const std::string& name) -> ClassScore& {
        ClassScore& c = classes[name];
        c.class_name = name;
        c.thing = options.is_thing(name);
        return c;
    };
    const auto add_to = [](ClassScore& c, int bin, auto&& fn) {
        fn(c.bins[static_cast<std::size_t>(bin)]);
        fn(c.bins[kAll]);
    };
    std::vector<bool> ref_used(reference.size(), false), est_used(estimate.size(), false);
    ev.matches = match_entities(reference, estimate, options, ref_used, est_used);
    // Matches with ignored references only keep their estimate from being spurious.
    ev.matches.erase(std::remove_if(ev.matches.begin(), ev.matches.end(),
                                    [&](const EntityMatch& m) { return ignored(m.reference); }),
                     ev.matches.end());
    std::sort(ev.matches.begin(), ev.matches.end(),
              [](const EntityMatch& a, const EntityMatch& b) { return a.reference < b.reference; });

    for (std::size_t r = 0; r < reference.size(); ++r) {
        const auto& ref = reference[r];
        if (!options.is_thing(ref.class_name) || !in_range(ref, options)) continue;
        if (ignored(r)) {
            ev.ignored.push_back(r);
            continue;
        }
        add_to(score_of(ref.class_name), distance_bin(bev_range_m(ref)), [&](ClassBinScore& b) {
            ++b.reference;
            if (!ref_used[r]) ++b.missed;
        });
        if (!ref_used[r]) ev.missed.push_back(r);
    }
    for (const auto& m : ev.matches) {
        const auto& ref = reference[m.reference];
        add_to(score_of(ref.class_name), distance_bin(bev_range_m(ref)), [&](ClassBinScore& b) {
            ++b.estimate;
            ++b.matched;
            if (m.bev_iou >= options.iou_threshold) ++b.good_iou;
            b.centre_errors_m.push_back(m.centre_error_m);
            b.heading_errors_deg.push_back(m.heading_error_rad * 180.0 / kPi);
            b.bev_ious.push_back(m.bev_iou);
            b.ious_3d.push_back(m.iou_3d);
            b.size_errors_m.push_back(m.size_error_m);
        });
    }
    for (std::size_t e = 0; e < estimate.size(); ++e) {
        const auto& est = estimate[e];
        if (est_used[e] || !in_range(est, options)) continue;
        if (!offends(est, reference, options)) continue;
        ev.spurious.push_back(e);
        add_to(score_of(est.class_name), distance_bin(bev_range_m(est)), [](ClassBinScore& b) {
            ++b.estimate;
            ++b.spurious;
        });
    }
    for (auto& [name, c] : classes) ev.classes.push_back(std::move(c));
    return ev;
}

std::vector<std::size_t> visible_instance_pixels(
    const std::filesystem::path& instance_png, const std::vector<scene_schema::Entity>& reference) {
    std::vector<std::size_t> count_of_id(65536, 0);
    for (const std::uint16_t id : read_instance_png(instance_png).values) ++count_of_id[id];
    std::map<int, int> ordinal;
    std::vector<std::size_t> visible(reference.size(), 0);
    for (std::size_t i = 0; i < reference.size(); ++i) {
        const int c = reference[i].class_id;
        if (c < 0 || c > 255) continue;
        const int n = ++ordinal[c];
        if (n > 255) continue;
        visible[i] = count_of_id[static_cast<std::size_t>(c << 8 | n)];
    }
    return visible;
}

std::vector<std::optional<ReferenceVisibility>> load_reference_visibility(
    const std::filesystem::path& visibility_json,
    const std::vector<scene_schema::Entity>& reference, const EntityEvalOptions& options) {
    const auto fail = [&](const std::string& what) {
        return std::runtime_error("cannot read visibility: " + what + " (" +
                                  visibility_json.string() + ")");
    };
    std::string text;
    try {
        text = stereoscene::support::read_text_input(visibility_json);
    } catch (const stereoscene::support::FileError& e) {
        throw fail(e.reason());
    }
    std::map<std::string, ReferenceVisibility> by_id;
    try {
        const nlohmann::json doc = scene_schema::parse_json(text);
        for (const auto& r : doc.at("entities")) {
            ReferenceVisibility v;
            v.visible_px = scene_schema::get_count(r.at("visible_px"), "visible_px");
            v.unoccluded_px = scene_schema::get_count(r.at("unoccluded_px"), "unoccluded_px");
            // Files without in_view_fraction predate it: the object is taken as wholly in view.
            v.in_view_fraction =
                r.contains("in_view_fraction") ? r.at("in_view_fraction").get<double>() : 1.0;
            if (!(v.in_view_fraction >= 0.0 && v.in_view_fraction <= 1.0)) {
                throw fail("in_view_fraction: must be in [0, 1]");
            }
            v.visible_fraction = v.unoccluded_px == 0
                                     ? 0.0
                                     : v.in_view_fraction * static_cast<double>(v.visible_px) /
                                           static_cast<double>(v.unoccluded_px);
            by_id[r.at("id").get<std::string>()] = v;
        }
    } catch (const nlohmann::json::exception& e) {
        throw fail(scene_schema::json_error_text(e));
    } catch (const scene_schema::SchemaError& e) {
        throw fail((e.pointer().empty() ? "" : e.pointer() + ": ") + e.rule());
    }
    std::vector<std::optional<ReferenceVisibility>> out(reference.size());
    for (std::size_t i = 0; i < reference.size(); ++i) {
        if (!options.is_thing(reference[i].class_name)) continue;
        const auto it = by_id.find(reference[i].id);
        if (it == by_id.end()) {
            throw fail("no record of reference entity '" + reference[i].id +
                       "' (rendered from another scene file?)");
        }
        out[i] = it->second;
    }
    return out;
}

void EvalBars::validate() const {
    if (class_name.empty()) throw std::invalid_argument("class_name: must not be empty");
    if (std::find(kDistanceBinEdges_m.begin(), kDistanceBinEdges_m.end(), max_range_m) ==
        kDistanceBinEdges_m.end()) {
        throw std::invalid_argument("max_range_m: must be a bin edge (10, 20, 30 or 50)");
    }
    if (require_recall > 1.0) throw std::invalid_argument("require_recall: must be <= 1");
    if (min_good_iou_fraction > 1.0) {
        throw std::invalid_argument("min_good_iou_fraction: must be <= 1");
    }
}

bool EvalBars::any() const {
    return require_recall >= 0.0 || max_spurious >= 0 || max_stuff_on_things >= 0 ||
           max_median_centre_error_m >= 0.0 || max_median_heading_error_deg >= 0.0 ||
           min_good_iou_fraction >= 0.0;
}

std::vector<std::string> check_bars(const EntityEvaluation& evaluation, const EvalBars& bars) {
    bars.validate();
    const ClassBinScore s = evaluation.within(bars.class_name, bars.max_range_m);
    std::vector<std::string> missed;
    const std::string where = " (" + bars.class_name + " within " +
                              std::to_string(static_cast<int>(bars.max_range_m)) + " m, ";
    if (bars.require_recall >= 0.0 && s.recall() < bars.require_recall) {
        missed.push_back("recall " + fmt(s.recall()) + " < " + fmt(bars.require_recall) + where +
                         std::to_string(s.matched) + "/" + std::to_string(s.reference) +
                         " found; --require-recall)");
    }
    if (bars.max_spurious >= 0 && s.spurious > static_cast<std::size_t>(bars.max_spurious)) {
        missed.push_back("spurious " + std::to_string(s.spurious) + " > " +
                         std::to_string(bars.max_spurious) + where + "--max-spurious)");
    }
    const std::size_t stuff = evaluation.stuff_on_things(bars.max_range_m);
    if (bars.max_stuff_on_things >= 0 &&
        stuff > static_cast<std::size_t>(bars.max_stuff_on_things)) {
        missed.push_back("stuff entities on things " + std::to_string(stuff) + " > " +
                         std::to_string(bars.max_stuff_on_things) + where +
                         "--max-stuff-on-things)");
    }
    const double centre = median(s.centre_errors_m);
    if (bars.max_median_centre_error_m >= 0.0 && centre > bars.max_median_centre_error_m) {
        missed.push_back("median centre error " + fmt(centre) + " m > " +
                         fmt(bars.max_median_centre_error_m) + where + std::to_string(s.matched) +
                         " matches; --max-median-centre-error)");
    }
    const double heading = median(s.heading_errors_deg);
    if (bars.max_median_heading_error_deg >= 0.0 && heading > bars.max_median_heading_error_deg) {
        missed.push_back("median heading error " + fmt(heading) + " deg > " +
                         fmt(bars.max_median_heading_error_deg) + where +
                         std::to_string(s.matched) + " matches; --max-median-heading-error)");
    }
    if (bars.min_good_iou_fraction >= 0.0 && s.good_iou_fraction() < bars.min_good_iou_fraction) {
        missed.push_back("BEV IoU >= " + fmt(evaluation.options.iou_threshold) + " for " +
                         fmt(s.good_iou_fraction()) + " < " + fmt(bars.min_good_iou_fraction) +
                         where + std::to_string(s.good_iou) + "/" + std::to_string(s.reference) +
                         "; --min-good-iou-fraction)");
    }
    return missed;
}

}  // namespace cloud_analysis
