#include "cloud_analysis/cluster.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include <pcl/kdtree/kdtree_flann.h>
#include <pcl/point_cloud.h>
#include <pcl/point_types.h>

namespace cloud_analysis {

void ClusterOptions::validate() const {
    if (!(distance_at_10m_m > 0.0))
        throw std::invalid_argument("cluster.distance_at_10m_m: must be > 0");
    if (!(growth >= 0.0)) throw std::invalid_argument("cluster.growth: must be >= 0");
    if (!(distance_max_m >= distance_at_10m_m)) {
        throw std::invalid_argument("cluster.distance_max_m: must be >= distance_at_10m_m");
    }
    if (min_points < 1) throw std::invalid_argument("cluster.min_points: must be >= 1");
}

double ClusterOptions::distance_at(double z_m) const {
    const double scale = z_m > 10.0 ? std::pow(z_m / 10.0, growth) : 1.0;
    return std::min(distance_at_10m_m * scale, distance_max_m);
}

std::vector<std::vector<std::size_t>> euclidean_clusters(
    const std::vector<Eigen::Vector3f>& points_m, const ClusterOptions& options) {
    options.validate();
    std::vector<std::vector<std::size_t>> clusters;
    if (points_m.empty()) return clusters;

    auto cloud = pcl::make_shared<pcl::PointCloud<pcl::PointXYZ>>();
    cloud->reserve(points_m.size());
    for (const auto& p : points_m) cloud->push_back(pcl::PointXYZ(p.x(), p.y(), p.z()));
    pcl::KdTreeFLANN<pcl::PointXYZ> tree;
    tree.setInputCloud(cloud);

    // Region growing: a neighbour joins when closer than the distance at the nearer depth.
    std::vector<char> visited(points_m.size(), 0);
    std::vector<int> found;
    std::vector<float> sq_dist;
    std::vector<std::size_t> queue;
    for (std::size_t seed = 0; seed < points_m.size(); ++seed) {
        if (visited[seed]) continue;
        visited[seed] = 1;
        queue.assign(1, seed);
        for (std::size_t head = 0; head < queue.size(); ++head) {
            const std::size_t i = queue[head];
            const double zi = points_m[i].z();
            const double radius = options.distance_at(zi);
            tree.radiusSearch(static_cast<int>(i), radius, found, sq_dist);
            for (std::size_t k = 0; k < found.size(); ++k) {
                const auto j = static_cast<std::size_t>(found[k]);
                if (visited[j]) continue;
                const double link = options.distance_at(std::min(zi, double{points_m[j].z()}));
                if (double{sq_dist[k]} > link * link) continue;
                visited[j] = 1;
                queue.push_back(j);
            }
        }
        if (queue.size() >= options.min_points) clusters.push_back(queue);
    }
    std::stable_sort(clusters.begin(), clusters.end(),
                     [](const auto& a, const auto& b) { return a.size() > b.size(); });
    return clusters;
}

}  // namespace cloud_analysis
