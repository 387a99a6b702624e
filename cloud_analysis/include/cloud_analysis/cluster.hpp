#pragma once

/// Euclidean clustering with a distance that grows with depth: stereo depth error grows as
/// dz = z^2 / (f B) * d_err, so the clustering distance is d10 * max(1, (z / 10 m)^growth).

#include <cstddef>
#include <vector>

#include <Eigen/Core>

namespace cloud_analysis {

/// Settings of euclidean_clusters.
struct ClusterOptions {
    double distance_at_10m_m = 0.5;  ///< clustering distance at 10 m depth, metres, > 0
    double growth = 2.0;             ///< exponent of the growth with z beyond 10 m, >= 0
    double distance_max_m = 3.0;     ///< cap of the grown distance, metres, >= distance_at_10m_m
    std::size_t min_points = 1;      ///< smaller clusters are dropped, >= 1
    /// Throws std::invalid_argument naming the bad field.
    void validate() const;
    /// Clustering distance at depth z_m, metres.
    double distance_at(double z_m) const;
};

/// Groups points: two points are linked when closer than the distance at the nearer one's
/// depth. Returns clusters (indices into points_m) sorted by size, largest first.
std::vector<std::vector<std::size_t>> euclidean_clusters(
    const std::vector<Eigen::Vector3f>& points_m, const ClusterOptions& options);

}  // namespace cloud_analysis
