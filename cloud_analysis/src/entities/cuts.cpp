#include "cloud_analysis/entities/cuts.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <map>

namespace cloud_analysis::instances {

std::optional<Eigen::Vector2d> truncation_point(const std::vector<Eigen::Vector3f>& pts,
                                                const std::vector<std::uint32_t>& pixels,
                                                const PixelGrid& grid, const Indices& members) {
    constexpr int kEdgeColumns = 8;  // the matcher leaves a ragged border of a few columns
    constexpr std::size_t kMinEdgePoints = 10;
    if (!grid.valid() || pixels.size() < pts.size()) return std::nullopt;
    Eigen::Vector2d left = Eigen::Vector2d::Zero(), right = Eigen::Vector2d::Zero();
    std::size_t n_left = 0, n_right = 0;
    const bool seen = grid.last_column > grid.first_column;
    const int first = seen ? grid.first_column : 0;
    const int last = seen ? grid.last_column : grid.width_px - 1;
    for (std::size_t i : members) {
        const int u = static_cast<int>(pixels[i] % static_cast<std::uint32_t>(grid.width_px));
        const Eigen::Vector2d ray(pts[i].x(), pts[i].z());
        const double left_edge = std::max<double>(first, grid.border.left_column(pts[i].z()));
        if (u < left_edge + kEdgeColumns) {
            left += ray;
            ++n_left;
        } else if (u > last - kEdgeColumns) {
            right += ray;
            ++n_right;
        }
    }
    if (std::max(n_left, n_right) < kMinEdgePoints) return std::nullopt;
    return n_left >= n_right ? Eigen::Vector2d(left / static_cast<double>(n_left))
                             : Eigen::Vector2d(right / static_cast<double>(n_right));
}

namespace {

/// The depth step that parts two surfaces at depth z: two disparity noises of 0.5 px, at least
/// 0.3 m (fb: the rig's focal length times baseline, px m; 0 when unknown).
double depth_step_m(double z, double fb) {
    constexpr double kDisparityNoisePx = 0.5;
    constexpr double kMinStepM = 0.3;
    return std::max(kMinStepM, 2.0 * (fb > 0.0 ? kDisparityNoisePx * z * z / fb : 0.0));
}

/// An object's members per image row, each row's as (column, member) pairs in member order.
using MemberRows = std::map<std::uint32_t, std::vector<std::pair<std::uint32_t, std::size_t>>>;
MemberRows member_rows(const std::vector<std::uint32_t>& pixels, const Indices& members,
                       std::uint32_t width_px) {
    MemberRows rows;
    for (std::size_t i : members) rows[pixels[i] / width_px].emplace_back(pixels[i] % width_px, i);
    return rows;
}

}  // namespace

std::optional<OcclusionCut> occlusion_cut(const std::vector<Eigen::Vector3f>& pts,
                                          const std::vector<std::uint32_t>& pixels,
                                          const PixelGrid& grid, const Indices& members,
                                          std::uint32_t instance, Indices* bleed,
                                          std::array<bool, 2>* sides_cut) {
    constexpr int kScanColumns = 12;
    constexpr std::size_t kBleedMembers = 8;
    constexpr std::size_t kMinRows = 5;
    if (!grid.valid() || grid.depth_m == nullptr || grid.instance_id == nullptr ||
        pixels.size() < pts.size()) {
        return std::nullopt;
    }
    const auto w = static_cast<std::uint32_t>(grid.width_px);
    const double fb = grid.border.fb_px_m > 0.0 ? grid.border.fb_px_m : 0.0;
    const auto step_at = [&](double z) { return depth_step_m(z, fb); };
    // Per image row, the members by column.
    MemberRows rows_of = member_rows(pixels, members, w);
    // Whether the first depth step beyond column u0 of row v, stepping `dir` past the object's
    // own pixels and pixels at depth z (its labels may fall short of its outline), is nearer;
    // `seen` when there is a step within kScanColumns.
    const auto occluded = [&](std::uint32_t v, std::uint32_t u0, double z, int dir, bool& seen) {
        for (int k = 1; k <= kScanColumns; ++k) {
            const long u = static_cast<long>(u0) + dir * k;
            if (u < 0 || u >= static_cast<long>(w)) return false;
            const std::size_t p = std::size_t{v} * w + static_cast<std::size_t>(u);
            if ((*grid.instance_id)[p] == instance) continue;
            const double zn = (*grid.depth_m)[p];
            if (!(zn > 0.0) || std::abs(zn - z) <= step_at(z)) continue;
            seen = true;
            return zn < z;
        }
        return false;
    };
    std::array<Eigen::Vector2d, 2> sum = {Eigen::Vector2d::Zero(), Eigen::Vector2d::Zero()};
    std::array<std::size_t, 2> cut = {0, 0}, seen_rows = {0, 0};
    for (auto& [v, row] : rows_of) {
        std::sort(row.begin(), row.end());
        for (int side = 0; side < 2; ++side) {
            // From the outline inwards: members with a nearer thing's disparity (foreground
            // fattening and labels past the outline) end at the first step to a farther depth
            // between neighbouring members among the kBleedMembers outermost.
            const auto at = [&](std::size_t k) {
                return side == 0 ? row[k] : row[row.size() - 1 - k];
            };
            std::size_t first = 0;
            for (std::size_t k = 0; k + 1 < row.size() && k < kBleedMembers; ++k) {
                const double z0 = pts[at(k).second].z(), z1 = pts[at(k + 1).second].z();
                if (z1 - z0 > step_at(z1)) {
                    first = k + 1;
                    break;
                }
            }
            const auto [u, i] = at(first);
            bool seen = false;
            const bool hidden = occluded(v, u, pts[i].z(), side == 0 ? -1 : 1, seen);
            seen_rows[side] += seen ? 1 : 0;
            if (!hidden) continue;
            ++cut[side];
            sum[side] += Eigen::Vector2d(pts[i].x(), pts[i].z());
            if (bleed != nullptr) {
                for (std::size_t k = 0; k < first; ++k) bleed->push_back(at(k).second);
            }
        }
    }
    if (bleed != nullptr) {
        // A short row's two ends may share members.
        std::sort(bleed->begin(), bleed->end());
        bleed->erase(std::unique(bleed->begin(), bleed->end()), bleed->end());
    }
    const auto is_cut = [&](int side) {
        return cut[side] >= kMinRows && 2 * cut[side] > seen_rows[side];
    };
    if (sides_cut != nullptr) *sides_cut = {is_cut(0), is_cut(1)};
    if (is_cut(0) == is_cut(1)) return std::nullopt;
    const int side = is_cut(0) ? 0 : 1;
    return OcclusionCut{Eigen::Vector2d(sum[side] / static_cast<double>(cut[side])),
                        side == 0 ? -1 : 1};
}

Indices occluders_inside(const std::vector<Eigen::Vector3f>& pts,
                         const std::vector<std::uint32_t>& pixels, const PixelGrid& grid,
                         const Indices& members) {
    Indices out;
    if (!grid.valid() || pixels.size() < pts.size()) return out;
    const auto w = static_cast<std::uint32_t>(grid.width_px);
    const double fb = grid.border.fb_px_m > 0.0 ? grid.border.fb_px_m : 0.0;
    MemberRows rows_of = member_rows(pixels, members, w);
    std::vector<std::size_t> starts;  // a row's runs: [starts[r], starts[r + 1])
    std::vector<double> depth;        // each run's median depth
    std::vector<double> z;
    for (auto& [v, row] : rows_of) {
        std::sort(row.begin(), row.end());
        starts.assign(1, 0);
        for (std::size_t k = 1; k < row.size(); ++k) {
            const double z0 = pts[row[k - 1].second].z(), z1 = pts[row[k].second].z();
            if (std::abs(z1 - z0) > depth_step_m(std::max(z0, z1), fb)) starts.push_back(k);
        }
        if (starts.size() < 3) continue;
        starts.push_back(row.size());
        depth.clear();
        for (std::size_t r = 0; r + 1 < starts.size(); ++r) {
            z.clear();
            for (std::size_t k = starts[r]; k < starts[r + 1]; ++k)
                z.push_back(pts[row[k].second].z());
            std::nth_element(z.begin(), z.begin() + static_cast<std::ptrdiff_t>(z.size() / 2),
                             z.end());
            depth.push_back(z[z.size() / 2]);
        }
        for (std::size_t r = 1; r + 1 < depth.size(); ++r) {
            const double step = depth_step_m(depth[r], fb);
            if (depth[r - 1] - depth[r] <= step || depth[r + 1] - depth[r] <= step) continue;
            for (std::size_t k = starts[r]; k < starts[r + 1]; ++k) out.push_back(row[k].second);
        }
    }
    std::sort(out.begin(), out.end());
    return out;
}

}  // namespace cloud_analysis::instances
