#pragma once

/// Euclidean clustering with a distance that grows with depth: stereo depth error grows as
/// dz = z^2 / (f B) * d_err, so the clustering distance is d10 * max(1, (z / 10 m)^growth).

#include <cstddef>
#include <cstdint>
#include <optional>
#include <vector>

#include <Eigen/Core>

namespace cloud_analysis {

/// Settings of euclidean_clusters.
struct ClusterOptions {
    double distance_at_10m_m = 0.5;  ///< clustering distance at 10 m depth, metres, > 0
    double growth = 2.0;             ///< exponent of the growth with z beyond 10 m, >= 0
    double distance_max_m = 3.0;     ///< cap of the grown distance, metres, in
                                     ///< [distance_at_10m_m, 1000 * distance_at_10m_m]
    std::size_t min_points = 1;      ///< smaller clusters are dropped, >= 1
    /// Exponent of the growth beyond 10 m of the distance across the viewing ray, horizontally
    /// (empty: growth, i.e. one distance in every direction). Stereo depth error runs along
    /// the ray, so a smaller exponent keeps two objects side by side apart (a parked car and
    /// the car passing beside it) without cutting a far object along its own depth smear.
    std::optional<double> cross_growth;  ///< >= 0 and <= growth
    /// The distance across the viewing ray at 10 m depth, metres (empty: distance_at_10m_m);
    /// in (0, distance_at_10m_m]. Across the ray stereo is as fine as the pixel (3 cm at 20 m
    /// for KITTI), so two objects side by side can be told apart closer than along it.
    std::optional<double> cross_distance_at_10m_m;
    /// Throws std::invalid_argument naming the bad field.
    void validate() const;
    /// Clustering distance at depth z_m, metres.
    double distance_at(double z_m) const;
    /// Distance across the viewing ray, horizontally, at depth z_m, metres (<= distance_at).
    double cross_distance_at(double z_m) const;
};

/// Groups points: two points are linked when closer than the distance at the nearer one's
/// depth (and, with cross_growth, when their horizontal offset across the viewing ray through
/// their midpoint is within the cross distance at the nearer one's depth). Returns clusters
/// (indices into points_m) sorted by size, largest first (ties in the order of their first point).
/// Neighbours are found on a hierarchical hash grid (cells of distance_at_10m_m * 2^level, a point
/// in the finest level whose cell holds its distance); cost about linear in the number of points.
std::vector<std::vector<std::size_t>> euclidean_clusters(
    const std::vector<Eigen::Vector3f>& points_m, const ClusterOptions& options);

/// Points grouped by cubic voxels: the centroid of each occupied voxel, voxels numbered in the
/// order of their first point.
struct VoxelGrid {
    std::vector<Eigen::Vector3f> centroid_m;  ///< mean of the voxel's points, metres
    std::vector<std::uint32_t> count;         ///< number of points in each voxel
    std::vector<std::uint32_t> voxel_of;      ///< voxel of each input point
};

/// Voxelizes points with cubic voxels of voxel_m metres (axis-aligned, origin at 0) whose edge
/// doubles at each of doubling_depths_m (ascending, at most 7): a point at depth z lies in a
/// voxel of voxel_m * 2^b, b the number of those depths <= z; voxels of different depth bands
/// are distinct even where they overlap in space. voxel_m <= 0 gives one voxel per point.
/// Throws std::invalid_argument for depths out of order or too many.
VoxelGrid voxelize(const std::vector<Eigen::Vector3f>& points_m, double voxel_m,
                   const std::vector<double>& doubling_depths_m = {});

}  // namespace cloud_analysis
