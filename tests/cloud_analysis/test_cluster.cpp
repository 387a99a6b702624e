#include <catch2/catch.hpp>

#include "cloud_analysis/cluster.hpp"

using cloud_analysis::ClusterOptions;
using cloud_analysis::euclidean_clusters;

namespace {

/// A 0.4 m cube of points (5 cm spacing) centred at c.
void add_blob(std::vector<Eigen::Vector3f>& pts, const Eigen::Vector3f& c) {
    for (float dx = -0.2f; dx <= 0.2f; dx += 0.05f) {
        for (float dy = -0.2f; dy <= 0.2f; dy += 0.05f) {
            for (float dz = -0.2f; dz <= 0.2f; dz += 0.05f)
                pts.push_back(c + Eigen::Vector3f(dx, dy, dz));
        }
    }
}

}  // namespace

TEST_CASE("two blobs 1 m apart at 10 m give two clusters", "[cluster]") {
    std::vector<Eigen::Vector3f> pts;
    add_blob(pts, {0.0f, 0.0f, 10.0f});
    add_blob(pts, {1.0f, 0.0f, 10.0f});
    ClusterOptions o;
    o.distance_at_10m_m = 0.5;  // the gap between the blobs is 0.6 m
    const auto clusters = euclidean_clusters(pts, o);
    REQUIRE(clusters.size() == 2);
    CHECK(clusters[0].size() == pts.size() / 2);
    CHECK(clusters[1].size() == pts.size() / 2);
    // Each cluster holds exactly one blob.
    for (const auto& c : clusters) {
        const float x0 = pts[c.front()].x();
        for (std::size_t i : c) CHECK(std::abs(pts[i].x() - x0) < 0.5f);
    }
}

TEST_CASE("the clustering distance grows with depth so far blobs merge", "[cluster]") {
    ClusterOptions o;
    o.distance_at_10m_m = 0.5;
    o.growth = 2.0;
    o.distance_max_m = 3.0;
    CHECK(o.distance_at(5.0) == Approx(0.5));
    CHECK(o.distance_at(20.0) == Approx(2.0));
    CHECK(o.distance_at(40.0) == Approx(3.0));
    std::vector<Eigen::Vector3f> pts;
    add_blob(pts, {0.0f, 0.0f, 30.0f});
    add_blob(pts, {1.0f, 0.0f, 30.0f});
    CHECK(euclidean_clusters(pts, o).size() == 1);
    o.growth = 0.0;
    CHECK(euclidean_clusters(pts, o).size() == 2);
}

TEST_CASE("clusters below min_points are dropped", "[cluster]") {
    std::vector<Eigen::Vector3f> pts;
    add_blob(pts, {0.0f, 0.0f, 10.0f});
    pts.emplace_back(5.0f, 0.0f, 10.0f);
    ClusterOptions o;
    o.min_points = 2;
    const auto clusters = euclidean_clusters(pts, o);
    REQUIRE(clusters.size() == 1);
    CHECK(clusters[0].size() == pts.size() - 1);
    o.distance_max_m = 0.1;
    CHECK_THROWS_WITH(o.validate(), Catch::Contains("distance_max_m"));
}
