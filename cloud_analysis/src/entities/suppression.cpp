#include "cloud_analysis/entities/suppression.hpp"

#include <algorithm>
#include <cmath>
#include <utility>
#include "stereoscene/support/angles.hpp"

namespace cloud_analysis::instances {

std::vector<Candidate> suppress_shadows(std::vector<Candidate> candidates,
                                        const std::vector<std::uint32_t>& pixels,
                                        const PixelGrid& grid, double min_gap_m,
                                        double max_shared_fraction, int radius_px) {
    if (!grid.valid() || candidates.size() < 2) return candidates;
    std::stable_sort(candidates.begin(), candidates.end(),
                     [](const auto& a, const auto& b) { return a.range_m < b.range_m; });
    // Per image row, the column extent of every accepted candidate's pixels on that row.
    struct Extent {
        int lo_px;
        int hi_px;
        float range_m;
        std::size_t group;
    };
    std::vector<std::vector<Extent>> rows(static_cast<std::size_t>(grid.height_px));
    const auto width = static_cast<std::uint32_t>(grid.width_px);
    std::vector<Candidate> kept;
    for (auto& c : candidates) {
        const int reach = c.fragment ? radius_px : 0;
        std::size_t shared = 0;
        for (std::size_t i : c.members) {
            const int u = static_cast<int>(pixels[i] % width);
            const int v = static_cast<int>(pixels[i] / width);
            bool inside = false;
            for (int r = std::max(0, v - reach);
                 r <= std::min(grid.height_px - 1, v + reach) && !inside; ++r) {
                for (const Extent& e : rows[static_cast<std::size_t>(r)]) {
                    if (e.group != c.group && double{e.range_m} + min_gap_m < c.range_m &&
                        u >= e.lo_px - reach && u <= e.hi_px + reach) {
                        inside = true;
                        break;
                    }
                }
            }
            shared += inside ? 1 : 0;
        }
        if (static_cast<double>(shared) >
            max_shared_fraction * static_cast<double>(c.members.size())) {
            continue;
        }
        std::vector<int> lo(rows.size(), grid.width_px), hi(rows.size(), -1);
        for (std::size_t i : c.members) {
            const int u = static_cast<int>(pixels[i] % width);
            const std::size_t v = pixels[i] / width;
            lo[v] = std::min(lo[v], u);
            hi[v] = std::max(hi[v], u);
        }
        for (std::size_t v = 0; v < rows.size(); ++v) {
            if (hi[v] >= 0)
                rows[v].push_back({lo[v], hi[v], static_cast<float>(c.range_m), c.group});
        }
        kept.push_back(std::move(c));
    }
    return kept;
}

std::vector<Candidate> suppress_nested(std::vector<Candidate> candidates) {
    std::stable_sort(candidates.begin(), candidates.end(), [](const auto& a, const auto& b) {
        return a.members.size() > b.members.size();
    });
    std::vector<Candidate> kept;
    for (auto& c : candidates) {
        bool nested = false;
        for (const auto& k : kept) {
            const double dx = c.box.centre_m.x() - k.box.centre_m.x();
            const double dz = c.box.centre_m.z() - k.box.centre_m.z();
            const BoxAxes axes(k.box.theta);
            const double along = axes.along(dx, dz), across = axes.across(dx, dz);
            if (std::abs(along) < k.box.L_m / 2.0 && std::abs(across) < k.box.W_m / 2.0) {
                nested = true;
                break;
            }
        }
        if (!nested) kept.push_back(std::move(c));
    }
    return kept;
}

double Footprint::distance_m(double px, double pz) const {
    const double dx = px - x, dz = pz - z;
    const double along = std::max(std::abs(axes.along(dx, dz)) - half_L, 0.0);
    const double across = std::max(std::abs(axes.across(dx, dz)) - half_W, 0.0);
    return std::hypot(along, across);
}

Footprint footprint_of(const OrientedBox& box) {
    return {box.centre_m.x(), box.centre_m.z(), BoxAxes(box.theta), box.L_m / 2.0, box.W_m / 2.0};
}

std::vector<Footprint> footprints_of(const std::vector<scene_schema::Entity>& things) {
    std::vector<Footprint> out;
    out.reserve(things.size());
    for (const auto& t : things) {
        out.push_back({t.x, t.z, BoxAxes(t.theta), t.L / 2.0, t.W / 2.0});
    }
    return out;
}

namespace {

/// Share of the footprint at (x, z), heading theta, L x W (sampled on a 10 x 10 grid of cell
/// centres) inside any of `things`.
double share_inside(double x0, double z0, double theta, double L, double W,
                    const std::vector<Footprint>& things) {
    constexpr int kSamples = 10;
    const double c = std::cos(theta), sn = std::sin(theta);
    int inside = 0;
    for (int i = 0; i < kSamples; ++i) {
        for (int j = 0; j < kSamples; ++j) {
            // Heading (cos t, -sin t) in x-z; across it (sin t, cos t).
            const double a = ((i + 0.5) / kSamples - 0.5) * L;
            const double b = ((j + 0.5) / kSamples - 0.5) * W;
            const double x = x0 + a * c + b * sn, z = z0 - a * sn + b * c;
            for (const auto& t : things) {
                const double dx = x - t.x, dz = z - t.z;
                if (std::abs(t.axes.along(dx, dz)) <= t.half_L &&
                    std::abs(t.axes.across(dx, dz)) <= t.half_W) {
                    ++inside;
                    break;
                }
            }
        }
    }
    return static_cast<double>(inside) / (kSamples * kSamples);
}

double share_inside(const OrientedBox& b, const std::vector<Footprint>& things) {
    return share_inside(b.centre_m.x(), b.centre_m.z(), b.theta, b.L_m, b.W_m, things);
}

}  // namespace

double footprint_share_inside(const scene_schema::Entity& e, const std::vector<Footprint>& things) {
    return share_inside(e.x, e.z, e.theta, e.L, e.W, things);
}

void turn_overlapping_objects(std::vector<Candidate>& candidates,
                              const std::vector<Eigen::Vector3f>& pts, BoxFitOptions fit,
                              const std::optional<GroundPlane>& ground) {
    constexpr double kOverlapShare = 0.25;  // a quarter of a box on another's ground
    using stereoscene::support::kHalfPi;
    const auto others = [&](std::size_t k) {
        std::vector<Footprint> out;
        for (std::size_t j = 0; j < candidates.size(); ++j) {
            if (j != k && candidates[j].instance != 0)
                out.push_back(footprint_of(candidates[j].box));
        }
        return out;
    };
    for (std::size_t k = 0; k < candidates.size(); ++k) {
        Candidate& c = candidates[k];
        if (c.instance == 0) continue;
        const std::vector<Footprint> around = others(k);
        const double share = share_inside(c.box, around);
        if (share <= kOverlapShare) continue;
        std::vector<Eigen::Vector3f> member_pts;
        member_pts.reserve(c.members.size());
        for (std::size_t i : c.members) member_pts.push_back(pts[i]);
        fit.yaw_rad = c.box.theta + kHalfPi;
        const OrientedBox turned = fit_upright_box(member_pts, ground, fit);
        if (share_inside(turned, around) <= share / 2.0) c.box = turned;
    }
}

double median_row_width_px(const Indices& members, const std::vector<std::uint32_t>& pixels,
                           const PixelGrid& grid) {
    if (!grid.valid() || members.empty()) return 0.0;
    // Points per image row, counted over the rows the members touch.
    std::vector<std::uint32_t> count(static_cast<std::size_t>(grid.height_px), 0);
    const auto width = static_cast<std::uint32_t>(grid.width_px);
    for (std::size_t i : members) ++count[pixels[i] / width];
    std::vector<double> per_row;
    for (const std::uint32_t n : count) {
        if (n > 0) per_row.push_back(static_cast<double>(n));
    }
    std::nth_element(per_row.begin(), per_row.begin() + per_row.size() / 2, per_row.end());
    return per_row[per_row.size() / 2];
}

std::vector<Candidate> drop_strips(std::vector<Candidate> candidates,
                                   const std::vector<std::uint32_t>& pixels, const PixelGrid& grid,
                                   double min_width_px) {
    if (!grid.valid() || min_width_px <= 0.0) return candidates;
    candidates.erase(std::remove_if(candidates.begin(), candidates.end(),
                                    [&](const Candidate& c) {
                                        return median_row_width_px(c.members, pixels, grid) <
                                               min_width_px;
                                    }),
                     candidates.end());
    return candidates;
}

std::vector<Candidate> drop_strips_beside(std::vector<Candidate> candidates,
                                          const std::vector<std::uint32_t>& pixels,
                                          const PixelGrid& grid, double width_px, int radius_px,
                                          double min_gap_m) {
    if (!grid.valid() || width_px <= 0.0 || candidates.size() < 2) return candidates;
    std::vector<char> narrow(candidates.size(), 0);
    for (std::size_t k = 0; k < candidates.size(); ++k) {
        narrow[k] = median_row_width_px(candidates[k].members, pixels, grid) < width_px ? 1 : 0;
    }
    if (std::find(narrow.begin(), narrow.end(), 1) == narrow.end()) return candidates;
    const auto width = static_cast<std::uint32_t>(grid.width_px);
    // Per candidate, per image row, its column extent (lo > hi: no pixels on the row).
    std::vector<std::vector<std::pair<int, int>>> extents(candidates.size());
    for (std::size_t k = 0; k < candidates.size(); ++k) {
        auto& rows = extents[k];
        rows.assign(static_cast<std::size_t>(grid.height_px), {grid.width_px, -1});
        for (std::size_t i : candidates[k].members) {
            auto& e = rows[pixels[i] / width];
            const int u = static_cast<int>(pixels[i] % width);
            e.first = std::min(e.first, u);
            e.second = std::max(e.second, u);
        }
    }
    std::vector<bool> drop(candidates.size(), false);
    for (std::size_t k = 0; k < candidates.size(); ++k) {
        const Candidate& c = candidates[k];
        if (!narrow[k]) continue;

        for (std::size_t o = 0; o < candidates.size() && !drop[k]; ++o) {
            const Candidate& big = candidates[o];
            if (o == k || big.group == c.group || big.members.size() <= c.members.size() ||
                std::abs(big.range_m - c.range_m) < min_gap_m) {
                continue;
            }
            std::size_t beside = 0;
            for (std::size_t i : c.members) {
                const auto& e = extents[o][pixels[i] / width];
                const int u = static_cast<int>(pixels[i] % width);
                beside +=
                    (e.first <= e.second && u >= e.first - radius_px && u <= e.second + radius_px)
                        ? 1
                        : 0;
            }
            drop[k] = 2 * beside >= c.members.size();
        }
    }
    std::vector<Candidate> kept;
    for (std::size_t k = 0; k < candidates.size(); ++k) {
        if (!drop[k]) kept.push_back(std::move(candidates[k]));
    }
    return kept;
}

}  // namespace cloud_analysis::instances
