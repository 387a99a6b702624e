#include "cloud_analysis/entities/image_components.hpp"

#include <algorithm>

namespace cloud_analysis::instances {

std::vector<Indices> image_components(const std::vector<Eigen::Vector3f>& pts,
                                      const std::vector<std::uint32_t>& pixels,
                                      const PixelGrid& grid, const ClusterOptions& co,
                                      int radius_px) {
    std::vector<long> at(static_cast<std::size_t>(grid.width_px) * grid.height_px, -1);
    for (std::size_t i = 0; i < pts.size(); ++i) at[pixels[i]] = static_cast<long>(i);
    std::vector<char> seen(pts.size(), 0);
    std::vector<Indices> out;
    for (std::size_t seed = 0; seed < pts.size(); ++seed) {
        if (seen[seed]) continue;
        seen[seed] = 1;
        Indices queue = {seed};
        for (std::size_t head = 0; head < queue.size(); ++head) {
            const std::size_t i = queue[head];
            const int u0 = static_cast<int>(pixels[i] % static_cast<std::uint32_t>(grid.width_px));
            const int v0 = static_cast<int>(pixels[i] / static_cast<std::uint32_t>(grid.width_px));
            for (int v = std::max(0, v0 - radius_px);
                 v <= std::min(grid.height_px - 1, v0 + radius_px); ++v) {
                for (int u = std::max(0, u0 - radius_px);
                     u <= std::min(grid.width_px - 1, u0 + radius_px); ++u) {
                    const long j = at[static_cast<std::size_t>(v) * grid.width_px + u];
                    if (j < 0 || seen[static_cast<std::size_t>(j)]) continue;
                    const auto& q = pts[static_cast<std::size_t>(j)];
                    const double link = co.distance_at(std::min(double{pts[i].z()}, double{q.z()}));
                    if (double{(pts[i] - q).squaredNorm()} > link * link) continue;
                    seen[static_cast<std::size_t>(j)] = 1;
                    queue.push_back(static_cast<std::size_t>(j));
                }
            }
        }
        out.push_back(std::move(queue));
    }
    return out;
}

}  // namespace cloud_analysis::instances
