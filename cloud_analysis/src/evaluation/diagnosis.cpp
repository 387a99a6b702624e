#include "cloud_analysis/evaluation/diagnosis.hpp"

#include <algorithm>
#include <cmath>
#include <map>
#include <stdexcept>

#include "cloud_analysis/io/io.hpp"
#include "stereoscene/support/angles.hpp"
#include "stereoscene/support/number_text.hpp"

using stereoscene::support::kPi;

namespace cloud_analysis {
namespace {

using stereoscene::support::fixed_text;

using Polygon = std::vector<Eigen::Vector2d>;

Polygon footprint(const scene_schema::Entity& e) {
    const auto c = footprint_corners(e);
    return Polygon(c.begin(), c.end());
}

/// Share of `of`'s footprint area that `by`'s footprint covers.
double covered_share(const scene_schema::Entity& of, const scene_schema::Entity& by) {
    const double area = of.W * of.L;
    return area > 0.0 ? convex_intersection_area(footprint(of), footprint(by)) / area : 0.0;
}

std::string pct(double share) { return fixed_text(100.0 * share, 0) + " %"; }

std::string box_size(const scene_schema::Entity& e) {
    return fixed_text(e.L, 1) + " x " + fixed_text(e.W, 1);
}

double bev_distance(const scene_schema::Entity& a, const scene_schema::Entity& b) {
    return std::hypot(a.x - b.x, a.z - b.z);
}

/// Classes on the ground: every box stands on them, so they explain nothing.
bool ground_class(const std::string& name) {
    return name == "road" || name == "sidewalk" || name == "parking" || name == "terrain" ||
           name == "ground" || name == "rail track";
}

struct Lookup {
    std::vector<long> match_of_ref, match_of_est;  // index into ev.matches, -1 none
    std::vector<bool> ignored;
};

Lookup lookup(std::size_t refs, std::size_t ests, const EntityEvaluation& ev) {
    Lookup l{std::vector<long>(refs, -1), std::vector<long>(ests, -1),
             std::vector<bool>(refs, false)};
    for (std::size_t i = 0; i < ev.matches.size(); ++i) {
        l.match_of_ref[ev.matches[i].reference] = static_cast<long>(i);
        l.match_of_est[ev.matches[i].estimate] = static_cast<long>(i);
    }
    for (const auto r : ev.ignored) l.ignored[r] = true;
    return l;
}

/// Why reference r was not matched.
Diagnosis missed_reason(std::size_t r, const std::vector<scene_schema::Entity>& reference,
                        const std::vector<scene_schema::Entity>& estimate,
                        const EntityEvaluation& ev, const Lookup& l) {
    const auto& ref = reference[r];
    long same = -1, other = -1;
    double same_share = 0.0, other_share = 0.0;
    for (std::size_t e = 0; e < estimate.size(); ++e) {
        const double s = covered_share(ref, estimate[e]);
        if (estimate[e].class_name == ref.class_name && s > same_share) {
            same = static_cast<long>(e);
            same_share = s;
        } else if (estimate[e].class_name != ref.class_name && s > other_share) {
            other = static_cast<long>(e);
            other_share = s;
        }
    }
    Diagnosis d{ref.id, "", ""};
    if (same >= 0 && same_share >= 0.05) {
        const auto& est = estimate[static_cast<std::size_t>(same)];
        const long m = l.match_of_est[static_cast<std::size_t>(same)];
        if (m >= 0) {
            d.kind = "merged";
            d.reason = "merged with " +
                       reference[ev.matches[static_cast<std::size_t>(m)].reference].id + " into " +
                       est.id + " (" + box_size(est) + " m box over " + pct(same_share) + " of it)";
        } else {
            // An unmatched box over two references is a merge whose centre fell between them.
            long partner = -1;
            for (std::size_t o = 0; o < reference.size() && partner < 0; ++o) {
                if (o != r && reference[o].class_name == ref.class_name &&
                    covered_share(reference[o], est) >= 0.15)
                    partner = static_cast<long>(o);
            }
            if (partner >= 0) {
                d.kind = "merged";
                d.reason = "merged with " + reference[static_cast<std::size_t>(partner)].id +
                           " into " + est.id + " (" + box_size(est) + " m box over " +
                           pct(same_share) + " of it, centre " +
                           fixed_text(bev_distance(est, ref), 2) + " m away: matched to neither)";
            } else {
                d.kind = "off-centre";
                d.reason = est.id + " (" + box_size(est) + " m) covers " + pct(same_share) +
                           " of it but its centre is " + fixed_text(bev_distance(est, ref), 2) +
                           " m away (> " + fixed_text(ev.options.max_match_distance_m, 1) + " m)";
            }
        }
    } else if (other >= 0 && other_share >= 0.3) {
        const auto& est = estimate[static_cast<std::size_t>(other)];
        d.kind = "other-class";
        d.reason =
            "boxed as " + est.class_name + " " + est.id + " (over " + pct(other_share) + " of it)";
    } else {
        d.kind = "no-box";
        long nearest = -1;
        for (std::size_t e = 0; e < estimate.size(); ++e) {
            if (estimate[e].class_name != ref.class_name) continue;
            if (nearest < 0 || bev_distance(estimate[e], ref) <
                                   bev_distance(estimate[static_cast<std::size_t>(nearest)], ref))
                nearest = static_cast<long>(e);
        }
        d.reason = "no box on it";
        if (nearest >= 0) {
            const auto& est = estimate[static_cast<std::size_t>(nearest)];
            d.reason += "; nearest " + ref.class_name + " box " + est.id + " is " +
                        fixed_text(bev_distance(est, ref), 1) + " m away";
        }
    }
    return d;
}

/// Why estimate e is spurious.
Diagnosis spurious_reason(std::size_t e, const std::vector<scene_schema::Entity>& reference,
                          const std::vector<scene_schema::Entity>& estimate,
                          const EntityEvaluation& ev, const Lookup& l) {
    const auto& est = estimate[e];
    Diagnosis d{est.id, "", ""};
    if (!ev.options.is_thing(est.class_name)) {
        d.kind = "stuff-on-thing";
        for (const auto& ref : reference) {
            if (ev.options.is_thing(ref.class_name) && covered_share(est, ref) >= 0.5)
                return {est.id, d.kind, est.class_name + " box on " + ref.id};
        }
        return {est.id, d.kind, est.class_name + " box on a thing"};
    }
    // Everything in the truth under the box, largest share of the box first.
    std::vector<std::pair<double, std::size_t>> under;
    for (std::size_t r = 0; r < reference.size(); ++r) {
        if (ground_class(reference[r].class_name)) continue;
        const double s = covered_share(est, reference[r]);
        if (s >= 0.05) under.push_back({s, r});
    }
    std::sort(under.rbegin(), under.rend());
    std::vector<std::pair<double, std::size_t>> same;
    for (const auto& u : under) {
        if (reference[u.second].class_name == est.class_name) same.push_back(u);
    }
    const auto owner = [&](std::size_t r) -> std::string {
        const long m = l.match_of_ref[r];
        if (m >= 0)
            return "matched by " + estimate[ev.matches[static_cast<std::size_t>(m)].estimate].id;
        return l.ignored[r] ? "not scored" : "unmatched";
    };
    if (same.size() >= 2 && same[1].first >= 0.15) {
        d.kind = "spans";
        d.reason = box_size(est) + " m box spans " + reference[same[0].second].id + " (" +
                   pct(same[0].first) + ", " + owner(same[0].second) + ") and " +
                   reference[same[1].second].id + " (" + pct(same[1].first) + ", " +
                   owner(same[1].second) + ")";
    } else if (!same.empty() && owner(same[0].second) == "unmatched") {
        const std::size_t r = same[0].second;
        d.kind = "off-centre";
        d.reason = "box on " + reference[r].id + " with its centre " +
                   fixed_text(bev_distance(est, reference[r]), 2) + " m off (> " +
                   fixed_text(ev.options.max_match_distance_m, 1) + " m; " + pct(same[0].first) +
                   " of the box on it)";
    } else if (!same.empty()) {
        const std::size_t r = same[0].second;
        d.kind = "duplicate";
        d.reason = "second box on " + reference[r].id + " (" + owner(r) + "; " +
                   pct(same[0].first) + " of the box on it, centre " +
                   fixed_text(bev_distance(est, reference[r]), 2) + " m off)";
    } else if (!under.empty()) {
        const auto& ref = reference[under[0].second];
        d.kind = "phantom";
        d.reason = "phantom over " + ref.class_name + " " + ref.id + " (" + pct(under[0].first) +
                   " of the box)";
    } else {
        d.kind = "phantom";
        long nearest = -1;
        for (std::size_t r = 0; r < reference.size(); ++r) {
            if (!ev.options.is_thing(reference[r].class_name)) continue;
            if (nearest < 0 || bev_distance(est, reference[r]) <
                                   bev_distance(est, reference[static_cast<std::size_t>(nearest)]))
                nearest = static_cast<long>(r);
        }
        d.reason = "phantom over nothing in the truth";
        if (nearest >= 0) {
            const auto& ref = reference[static_cast<std::size_t>(nearest)];
            d.reason += "; nearest thing " + ref.id + " is " +
                        fixed_text(bev_distance(est, ref), 1) + " m away";
        }
    }
    return d;
}

}  // namespace

std::vector<Diagnosis> diagnose_entities(
    const std::vector<scene_schema::Entity>& reference,
    const std::vector<scene_schema::Entity>& estimate, const EntityEvaluation& ev,
    const std::vector<std::optional<ReferenceVisibility>>& visibility) {
    const Lookup l = lookup(reference.size(), estimate.size(), ev);
    std::vector<Diagnosis> out;
    for (const auto r : ev.missed) {
        Diagnosis d = missed_reason(r, reference, estimate, ev, l);
        if (r < visibility.size() && visibility[r])
            d.reason += "; visible " + fixed_text(visibility[r]->visible_fraction, 2);
        out.push_back(d);
    }
    for (const auto& m : ev.matches) {
        if (m.bev_iou >= ev.options.iou_threshold) continue;
        const auto& ref = reference[m.reference];
        const auto& est = estimate[m.estimate];
        out.push_back({ref.id, "under-covered",
                       est.id + " covers " + pct(covered_share(ref, est)) + " of it (box " +
                           box_size(est) + " m vs " + box_size(ref) + " m, centre " +
                           fixed_text(m.bev_centre_error_m, 2) + " m off, heading " +
                           fixed_text(m.heading_error_rad * 180.0 / kPi, 0) + " deg off, BEV IoU " +
                           fixed_text(m.bev_iou, 2) + ")"});
    }
    for (const auto e : ev.spurious) out.push_back(spurious_reason(e, reference, estimate, ev, l));
    return out;
}

InstanceImage load_instance_image(const std::filesystem::path& instance_png,
                                  const Palette& palette) {
    ImageU16 image = read_instance_png(instance_png);
    InstanceImage out;
    out.width_px = image.width_px;
    out.height_px = image.height_px;
    out.values = std::move(image.values);
    out.label_name.assign(256, "");
    for (const auto& c : palette.classes) {
        if (c.id >= 0 && c.id < 256) out.label_name[static_cast<std::size_t>(c.id)] = c.name;
    }
    return out;
}

namespace {

/// "vegetation 61 %, car 20 %": the classes of the instance image inside a rectangle.
std::string classes_in_rect(const InstanceImage& image, const Eigen::Vector4d& rect) {
    std::map<std::string, std::size_t> count;
    std::size_t total = 0;
    const int u0 = std::max(0, static_cast<int>(std::floor(rect[0])));
    const int v0 = std::max(0, static_cast<int>(std::floor(rect[1])));
    const int u1 = std::min(image.width_px, static_cast<int>(std::ceil(rect[2])));
    const int v1 = std::min(image.height_px, static_cast<int>(std::ceil(rect[3])));
    for (int v = v0; v < v1; ++v) {
        for (int u = u0; u < u1; ++u) {
            const std::uint16_t value =
                image.values[static_cast<std::size_t>(v) * image.width_px + u];
            const std::string& name = image.label_name[value >> 8];
            ++count[name.empty() ? "label " + std::to_string(value >> 8) : name];
            ++total;
        }
    }
    std::vector<std::pair<std::size_t, std::string>> sorted;
    for (const auto& [name, n] : count) sorted.push_back({n, name});
    std::sort(sorted.rbegin(), sorted.rend());
    std::string text;
    for (std::size_t i = 0; i < sorted.size() && i < 3; ++i) {
        if (!text.empty()) text += ", ";
        text += sorted[i].second + " " +
                pct(static_cast<double>(sorted[i].first) / static_cast<double>(total));
    }
    return text;
}

}  // namespace

namespace {

/// What diagnose_cars knows of the matches.
struct CarMatchIndex {
    const std::vector<scene_schema::Entity>& entities;
    const std::vector<GtCar>& gt;
    const CarEvaluation& ev;
    const CarMatchOptions& options;
    std::vector<long> match_of_gt, match_of_entity;  ///< index into ev.matches, or -1
    std::string gt_name(std::size_t g) const { return "GT car " + std::to_string(gt[g].instance); }
};

/// Why GT car g, owed and unmatched, was missed.
Diagnosis why_missed(const CarMatchIndex& x, std::size_t g) {
    const auto& [entities, gt, ev, options, match_of_gt, match_of_entity] = x;
    const GtCar& car = gt[g];
    const double grow = 2.0 * options.footprint_margin_m;
    const auto gt_name = [&](std::size_t k) { return x.gt_name(k); };
    long best = -1;
    double best_share = 0.0;
    for (std::size_t i = 0; i < entities.size(); ++i) {
        if (entities[i].class_name != options.car_class) continue;
        const double f =
            footprint_inside_fraction(entities[i], car.points_m, options.footprint_margin_m);
        if (f > best_share) {
            best = static_cast<long>(i);
            best_share = f;
        }
    }
    Diagnosis d{gt_name(g), "", ""};
    const std::string where = " (" + std::to_string(car.pixel_count) + " GT px at " +
                              fixed_text(car.range_m(), 1) + " m)";
    if (best < 0) {
        d.kind = "no-box";
        d.reason = "no car box holds any of its points" + where;
    } else {
        const auto& e = entities[static_cast<std::size_t>(best)];
        const long m = match_of_entity[static_cast<std::size_t>(best)];
        const double area = (e.L + grow) * (e.W + grow);
        if (area > options.max_footprint_area_m2) {
            d.kind = "too-large";
            d.reason = e.id + " holds " + pct(best_share) + " of its points but its grown " +
                       "footprint is " + fixed_text(area, 1) + " m2 (> " +
                       fixed_text(options.max_footprint_area_m2, 0) + ")" + where;
        } else if (m >= 0 && best_share >= options.min_inside_fraction) {
            d.kind = "merged";
            d.reason = "merged with " + gt_name(ev.matches[static_cast<std::size_t>(m)].gt) +
                       " into " + e.id + " (" + box_size(e) + " m box holds " + pct(best_share) +
                       " of its points)" + where;
        } else {
            d.kind = "under-covered";
            d.reason =
                e.id + " (" + box_size(e) + " m" +
                (m >= 0 ? ", matched to " + gt_name(ev.matches[static_cast<std::size_t>(m)].gt)
                        : std::string()) +
                ") holds only " + pct(best_share) + " of its points (< " +
                pct(options.min_inside_fraction) + ")" + where;
        }
    }
    return d;
}

/// Why car entity e, in range and unmatched, matches nothing: a second box on a car, or a
/// phantom (with what its image box shows).
Diagnosis why_spurious(const CarMatchIndex& x, const scene_schema::Entity& e,
                       const InstanceImage* image, const StereoCamera* camera) {
    const auto& [entities, gt, ev, options, match_of_gt, match_of_entity] = x;
    const auto gt_name = [&](std::size_t k) { return x.gt_name(k); };
    long best = -1;
    double best_share = 0.0;
    for (std::size_t g = 0; g < gt.size(); ++g) {
        const double f = footprint_inside_fraction(e, gt[g].points_m, options.footprint_margin_m);
        if (f > best_share) {
            best = static_cast<long>(g);
            best_share = f;
        }
    }
    Diagnosis d{e.id, "", ""};
    if (best >= 0 && best_share >= 0.05) {
        const auto g = static_cast<std::size_t>(best);
        const long m = match_of_gt[g];
        d.kind = "duplicate";
        d.reason =
            "holds " + pct(best_share) + " of " + gt_name(g) + "'s points (" +
            (m >= 0 ? "matched by " + entities[ev.matches[static_cast<std::size_t>(m)].entity].id
                    : std::string(gt[g].pixel_count < options.min_gt_pixels ? "not owed"
                                                                            : "unmatched")) +
            ")";
    } else {
        d.kind = "phantom";
        d.reason =
            "phantom at " + fixed_text(std::hypot(e.x, e.z), 1) + " m, no GT car point inside";
        if (image && camera) {
            const auto rect = projected_box_px(e, *camera, image->width_px, image->height_px);
            if (rect) d.reason += "; its image box shows " + classes_in_rect(*image, *rect);
        }
    }
    return d;
}

}  // namespace

std::vector<Diagnosis> diagnose_cars(const std::vector<scene_schema::Entity>& entities,
                                     const std::vector<GtCar>& gt, const CarEvaluation& ev,
                                     const CarMatchOptions& options, const InstanceImage* image,
                                     const StereoCamera* camera) {
    CarMatchIndex x{entities,
                    gt,
                    ev,
                    options,
                    std::vector<long>(gt.size(), -1),
                    std::vector<long>(entities.size(), -1)};
    for (std::size_t i = 0; i < ev.matches.size(); ++i) {
        x.match_of_gt[ev.matches[i].gt] = static_cast<long>(i);
        x.match_of_entity[ev.matches[i].entity] = static_cast<long>(i);
    }
    std::vector<Diagnosis> out;
    for (std::size_t g = 0; g < gt.size(); ++g) {
        const GtCar& car = gt[g];
        if (x.match_of_gt[g] >= 0 || car.range_m() > options.max_range_m ||
            car.pixel_count < options.min_gt_pixels)
            continue;
        out.push_back(why_missed(x, g));
    }
    for (std::size_t i = 0; i < entities.size(); ++i) {
        const auto& e = entities[i];
        if (e.class_name != options.car_class || x.match_of_entity[i] >= 0 ||
            std::hypot(e.x, e.z) > options.max_range_m)
            continue;
        out.push_back(why_spurious(x, e, image, camera));
    }
    return out;
}

}  // namespace cloud_analysis
