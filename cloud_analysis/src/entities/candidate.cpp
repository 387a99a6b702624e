#include "cloud_analysis/entities/candidate.hpp"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <utility>

namespace cloud_analysis::instances {

ClassFit class_fit(const ClassSettings& s) {
    ClassFit f;
    f.cluster.distance_at_10m_m = s.cluster_distance_m;
    f.cluster.growth = s.cluster_growth;
    f.cluster.cross_growth = s.cluster_cross_growth;
    f.cluster.cross_distance_at_10m_m = s.cluster_cross_distance_m;
    f.cluster.distance_max_m = s.cluster_distance_max_m;
    f.cluster.min_points = 1;
    if (s.thing && s.has_prior()) {
        f.box.prior_L_m = s.prior_L_m;
        f.box.prior_W_m = s.prior_W_m;
        f.box.prior_H_m = s.prior_H_m;
    }
    f.box.rest_on_ground = s.thing;
    return f;
}

scene_schema::Entity make_entity(const ClassInfo& info, const OrientedBox& box,
                                 std::size_t point_count, double confidence,
                                 const std::string& method) {
    scene_schema::Entity e;
    e.class_name = info.name;
    e.class_id = info.id;
    e.x = box.centre_m.x();
    e.y = box.centre_m.y();
    e.z = box.centre_m.z();
    e.theta = box.theta;
    e.L = std::max(box.L_m, 1e-3);
    e.W = std::max(box.W_m, 1e-3);
    e.H = std::max(box.H_m, 1e-3);
    e.point_count = static_cast<std::int64_t>(point_count);
    e.confidence = std::clamp(confidence, 0.0, 1.0);
    e.method = method;
    return e;
}

double seen_area_m2(const std::vector<Eigen::Vector3f>& pts, const Indices& members, double fx_px,
                    double fy_px) {
    double sum = 0.0;
    for (std::size_t i : members) sum += double{pts[i].z()} * double{pts[i].z()};
    return sum / (fx_px * fy_px);
}

double confidence_of(std::size_t n, const ClassSettings& s) {
    const double dn = static_cast<double>(n);
    return dn / (dn + 2.0 * s.min_points);
}

void keep_largest(std::vector<scene_schema::Entity>& entities, int max_entities) {
    std::stable_sort(entities.begin(), entities.end(),
                     [](const auto& a, const auto& b) { return a.point_count > b.point_count; });
    if (entities.size() > static_cast<std::size_t>(max_entities)) {
        entities.resize(static_cast<std::size_t>(max_entities));
    }
}

Indices densest_range_window(const std::vector<Eigen::Vector3f>& pts, const Indices& members,
                             double extent_m, std::size_t min_points) {
    if (members.size() < 2 || !(extent_m > 0.0)) return members;
    std::vector<std::pair<double, std::size_t>> by_range;
    by_range.reserve(members.size());
    for (std::size_t i : members) {
        by_range.emplace_back(std::hypot(double{pts[i].x()}, double{pts[i].z()}), i);
    }
    std::sort(by_range.begin(), by_range.end());
    std::size_t best_first = 0, best_count = 0;
    for (std::size_t first = 0, last = 0; first < by_range.size(); ++first) {
        while (last < by_range.size() && by_range[last].first <= by_range[first].first + extent_m) {
            ++last;
        }
        if (last - first > best_count) {
            best_count = last - first;
            best_first = first;
        }
    }
    if (best_count < min_points || best_count == members.size()) return members;
    Indices kept;
    kept.reserve(best_count);
    for (std::size_t k = best_first; k < best_first + best_count; ++k) {
        kept.push_back(by_range[k].second);
    }
    std::sort(kept.begin(), kept.end());
    return kept;
}

}  // namespace cloud_analysis::instances
