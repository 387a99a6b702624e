#include "cloud_analysis/entities/cuts.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <unordered_map>

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

std::optional<std::pair<Eigen::Vector2d, int>> occlusion_cut(
    const std::vector<Eigen::Vector3f>& pts, const std::vector<std::uint32_t>& pixels,
    const PixelGrid& grid, const Indices& members, std::uint32_t instance) {
    constexpr int kScanColumns = 12;
    constexpr std::size_t kMinRows = 5;
    constexpr double kDisparityNoisePx = 0.5;  // a step this many disparity noises deep, at least
    constexpr double kMinStepM = 0.3;
    if (!grid.valid() || grid.depth_m == nullptr || grid.instance_id == nullptr ||
        pixels.size() < pts.size()) {
        return std::nullopt;
    }
    const int w = grid.width_px;
    // Per image row, the object's outermost member points on the left and the right.
    std::unordered_map<int, std::pair<std::size_t, std::size_t>> ends;
    for (std::size_t i : members) {
        const int v = static_cast<int>(pixels[i] / static_cast<std::uint32_t>(w));
        const auto u = [&](std::size_t k) { return pixels[k] % static_cast<std::uint32_t>(w); };
        const auto [it, added] = ends.try_emplace(v, i, i);
        if (added) continue;
        if (u(i) < u(it->second.first)) it->second.first = i;
        if (u(i) > u(it->second.second)) it->second.second = i;
    }
    const double fb = grid.border.fb_px_m > 0.0 ? grid.border.fb_px_m : 0.0;
    // Whether the first depth step beyond the member's pixel, stepping `dir` past the object's
    // own pixels and pixels at its depth (its labels may fall short of its outline), is
    // nearer; `seen` when there is a step within kScanColumns.
    const auto occluded = [&](std::size_t i, int dir, bool& seen) {
        const int v = static_cast<int>(pixels[i] / static_cast<std::uint32_t>(w));
        const int u0 = static_cast<int>(pixels[i] % static_cast<std::uint32_t>(w));
        const double z = pts[i].z();
        const double step =
            std::max(kMinStepM, 2.0 * (fb > 0.0 ? kDisparityNoisePx * z * z / fb : 0.0));
        for (int k = 1; k <= kScanColumns; ++k) {
            const int u = u0 + dir * k;
            if (u < 0 || u >= w) return false;
            const std::size_t p = static_cast<std::size_t>(v) * static_cast<std::size_t>(w) +
                                  static_cast<std::size_t>(u);
            if ((*grid.instance_id)[p] == instance) continue;
            const double zn = (*grid.depth_m)[p];
            if (!(zn > 0.0) || std::abs(zn - z) <= step) continue;
            seen = true;
            return zn < z;
        }
        return false;
    };
    std::array<Eigen::Vector2d, 2> sum = {Eigen::Vector2d::Zero(), Eigen::Vector2d::Zero()};
    std::array<std::size_t, 2> cut = {0, 0}, rows = {0, 0};
    for (const auto& [v, lr] : ends) {
        for (int side = 0; side < 2; ++side) {
            const std::size_t i = side == 0 ? lr.first : lr.second;
            bool seen = false;
            const bool hidden = occluded(i, side == 0 ? -1 : 1, seen);
            rows[side] += seen ? 1 : 0;
            if (!hidden) continue;
            ++cut[side];
            sum[side] += Eigen::Vector2d(pts[i].x(), pts[i].z());
        }
    }
    const auto is_cut = [&](int side) {
        return cut[side] >= kMinRows && 2 * cut[side] > rows[side];
    };
    if (is_cut(0) == is_cut(1)) return std::nullopt;
    const int side = is_cut(0) ? 0 : 1;
    return std::make_pair(Eigen::Vector2d(sum[side] / static_cast<double>(cut[side])),
                          side == 0 ? -1 : 1);
}

}  // namespace cloud_analysis::instances
