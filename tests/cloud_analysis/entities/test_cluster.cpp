#include <algorithm>
#include <array>
#include <cmath>
#include <map>
#include <random>
#include <vector>

#include <catch2/catch.hpp>

#include "cloud_analysis/entities/cluster.hpp"

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

namespace {

/// Points on a vertical strip along the viewing ray through (x, z): a car's side face seen at
/// a grazing angle, `length` metres along the ray, 1 m high, 5 cm apart.
void add_face_along_ray(std::vector<Eigen::Vector3f>& pts, float x, float z, float length) {
    const Eigen::Vector3f ray = Eigen::Vector3f(x, 0.0f, z).normalized();
    for (float s = -0.5f * length; s <= 0.5f * length; s += 0.05f) {
        for (float y = 0.0f; y <= 1.0f; y += 0.05f) {
            pts.push_back(Eigen::Vector3f(x, y, z) + s * ray);
        }
    }
}

/// The car class's clustering distances: 0.4 m at 10 m, growing with z^2, at most 1.5 m.
ClusterOptions car_clustering() {
    ClusterOptions o;
    o.distance_at_10m_m = 0.4;
    o.growth = 2.0;
    o.distance_max_m = 1.5;
    return o;
}

/// Two 4 m side faces along the viewing ray at 16 m, the second `gap_m` beyond the first
/// across the ray; returns the index of the second face's first point.
std::size_t add_faces_across_ray(std::vector<Eigen::Vector3f>& pts, float gap_m) {
    add_face_along_ray(pts, 3.0f, 16.0f, 4.0f);
    const Eigen::Vector3f across = Eigen::Vector3f(16.0f, 0.0f, -3.0f).normalized();
    const std::size_t first = pts.size();
    add_face_along_ray(pts, 3.0f + gap_m * across.x(), 16.0f + gap_m * across.z(), 4.0f);
    return first;
}

}  // namespace

TEST_CASE("across the viewing ray the distance grows by its own exponent", "[cluster]") {
    ClusterOptions o = car_clustering();
    // A parked car's side face and the side of the car passing beside it, 0.6 m apart across
    // the ray at 16 m: the grown distance (1.02 m) links them, the cross distance (0.4 m) not.
    std::vector<Eigen::Vector3f> pts;
    const std::size_t first = add_faces_across_ray(pts, 0.6f);
    CHECK(euclidean_clusters(pts, o).size() == 1);
    o.cross_growth = 0.0;
    CHECK(o.cross_distance_at(16.0) == Approx(0.4));
    CHECK(o.distance_at(16.0) == Approx(1.024));
    const auto apart = euclidean_clusters(pts, o);
    REQUIRE(apart.size() == 2);
    CHECK(apart[0].size() == first);
    // Along the ray the grown distance still holds: a face whose depth smear has a 0.7 m gap
    // (more than the cross distance, within the grown one) stays one cluster.
    std::vector<Eigen::Vector3f> smear;
    add_face_along_ray(smear, 3.0f, 15.0f, 2.0f);  // 15.30 m from the camera, 2 m long
    const float beyond = (15.297f + 1.0f + 0.7f + 0.5f) / 15.297f;  // 0.7 m gap, 1 m long
    add_face_along_ray(smear, 3.0f * beyond, 15.0f * beyond, 1.0f);
    CHECK(euclidean_clusters(smear, o).size() == 1);
    ClusterOptions bad = o;
    bad.cross_growth = 2.5;  // more than growth
    CHECK_THROWS_WITH(bad.validate(), Catch::Contains("cross_growth"));
    bad.cross_growth = -1.0;
    CHECK_THROWS_WITH(bad.validate(), Catch::Contains("cross_growth"));
}

TEST_CASE("the distance across the viewing ray has its own base", "[cluster]") {
    ClusterOptions o = car_clustering();
    o.cross_growth = 0.0;
    // Two side faces 0.35 m apart across the ray at 16 m: linked within 0.4 m, apart within 0.3.
    std::vector<Eigen::Vector3f> pts;
    add_faces_across_ray(pts, 0.35f);
    CHECK(euclidean_clusters(pts, o).size() == 1);
    o.cross_distance_at_10m_m = 0.3;
    CHECK(o.cross_distance_at(16.0) == Approx(0.3));
    CHECK(o.distance_at(16.0) == Approx(1.024));  // along the ray unchanged
    CHECK(euclidean_clusters(pts, o).size() == 2);
    // Without cross_growth the base grows with the clustering exponent.
    o.cross_growth.reset();
    CHECK(o.cross_distance_at(20.0) == Approx(1.2));
    ClusterOptions bad = o;
    bad.cross_distance_at_10m_m = 0.5;  // more than the clustering distance
    CHECK_THROWS_WITH(bad.validate(), Catch::Contains("cross_distance_at_10m_m"));
    bad.cross_distance_at_10m_m = 0.0;
    CHECK_THROWS_WITH(bad.validate(), Catch::Contains("cross_distance_at_10m_m"));
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

namespace {

/// Clusters of a brute-force reference: every pair tested, union-find, as sorted index sets.
std::vector<std::vector<std::size_t>> reference_clusters(const std::vector<Eigen::Vector3f>& pts,
                                                         const ClusterOptions& o) {
    std::vector<std::size_t> parent(pts.size());
    for (std::size_t i = 0; i < pts.size(); ++i) parent[i] = i;
    const auto root = [&](std::size_t i) {
        while (parent[i] != i) i = parent[i] = parent[parent[i]];
        return i;
    };
    for (std::size_t i = 0; i < pts.size(); ++i) {
        for (std::size_t j = i + 1; j < pts.size(); ++j) {
            const double link = o.distance_at(std::min(double{pts[i].z()}, double{pts[j].z()}));
            if (double{(pts[i] - pts[j]).squaredNorm()} <= link * link) parent[root(i)] = root(j);
        }
    }
    std::vector<std::vector<std::size_t>> by_root(pts.size());
    for (std::size_t i = 0; i < pts.size(); ++i) by_root[root(i)].push_back(i);
    std::vector<std::vector<std::size_t>> out;
    for (auto& c : by_root) {
        if (c.size() >= o.min_points) out.push_back(std::move(c));
    }
    std::sort(out.begin(), out.end());
    return out;
}

std::vector<std::vector<std::size_t>> as_sorted_sets(std::vector<std::vector<std::size_t>> c) {
    for (auto& members : c) std::sort(members.begin(), members.end());
    std::sort(c.begin(), c.end());
    return c;
}

/// Random blobs of random size and spread at depths 2-60 m, some overlapping.
std::vector<Eigen::Vector3f> random_blobs(std::uint32_t seed, int blobs, int points_per_blob) {
    std::mt19937 rng(seed);
    std::uniform_real_distribution<float> x(-20.0f, 20.0f), y(-3.0f, 2.0f), z(2.0f, 60.0f);
    std::uniform_real_distribution<float> spread(0.05f, 1.5f);
    std::normal_distribution<float> unit(0.0f, 1.0f);
    std::vector<Eigen::Vector3f> pts;
    for (int b = 0; b < blobs; ++b) {
        const Eigen::Vector3f c(x(rng), y(rng), z(rng));
        const float s = spread(rng);
        for (int k = 0; k < points_per_blob; ++k) {
            pts.push_back(c + s * Eigen::Vector3f(unit(rng), unit(rng), unit(rng)));
        }
    }
    std::shuffle(pts.begin(), pts.end(), rng);
    return pts;
}

}  // namespace

TEST_CASE("the grid clustering finds the clusters of a brute-force reference on random blobs",
          "[cluster]") {
    // Settings of cars, of stuff classes, of small things, without growth, and a cap far
    // above the distance at 10 m (many grid levels).
    const std::vector<std::array<double, 3>> settings = {
        {0.4, 2.0, 1.5}, {1.0, 1.0, 2.0}, {0.3, 2.0, 1.0}, {0.5, 0.0, 0.5}, {0.2, 3.0, 5.0}};
    for (std::uint32_t seed = 1; seed <= 4; ++seed) {
        const auto pts = random_blobs(seed, 40, 60);
        for (const auto& [d10, growth, cap] : settings) {
            ClusterOptions o;
            o.distance_at_10m_m = d10;
            o.growth = growth;
            o.distance_max_m = cap;
            o.min_points = seed % 2 == 0 ? 1 : 5;
            const auto clusters = euclidean_clusters(pts, o);
            // Largest first, and the same partition as the reference.
            for (std::size_t k = 1; k < clusters.size(); ++k) {
                CHECK(clusters[k - 1].size() >= clusters[k].size());
            }
            const auto expected = reference_clusters(pts, o);
            INFO("seed " << seed << ", d10 " << d10 << ", growth " << growth << ", cap " << cap);
            CHECK(expected.size() > 3);
            CHECK(as_sorted_sets(clusters) == expected);
        }
    }
}

TEST_CASE("the grid clustering finds the reference's clusters when the points span kilometres",
          "[cluster]") {
    // Blobs scattered over 40 km: a dense cell array over their bounding box would take
    // gigabytes, so the cells are hashed; the clusters must not change.
    auto pts = random_blobs(7, 30, 40);
    for (std::size_t i = 0; i < pts.size(); ++i) {
        const float far = static_cast<float>((i * 2654435761u) % 5) * 10000.0f - 20000.0f;
        pts[i].x() += far;
    }
    ClusterOptions o;
    o.distance_at_10m_m = 0.4;
    o.growth = 2.0;
    o.distance_max_m = 1.5;
    const auto expected = reference_clusters(pts, o);
    CHECK(expected.size() > 3);
    CHECK(as_sorted_sets(euclidean_clusters(pts, o)) == expected);
}

TEST_CASE("points exactly one clustering distance apart link, a little farther do not",
          "[cluster]") {
    // A chain along x at 5 m depth (distance 0.5 m): steps of 0.5 m link, 0.5001 m does not;
    // the chain straddles zero so that negative grid cells are crossed too.
    ClusterOptions o;
    o.distance_at_10m_m = 0.5;
    std::vector<Eigen::Vector3f> pts;
    for (int k = -4; k <= 4; ++k) pts.emplace_back(0.5f * static_cast<float>(k), 0.0f, 5.0f);
    CHECK(euclidean_clusters(pts, o).size() == 1);
    pts.emplace_back(2.0f + 0.5001f, 0.0f, 5.0f);
    const auto clusters = euclidean_clusters(pts, o);
    REQUIRE(clusters.size() == 2);
    CHECK(clusters[0].size() == 9);
    CHECK(clusters[1] == std::vector<std::size_t>{9});
}

TEST_CASE("voxelize numbers voxels by first point and gives each the mean of its points",
          "[cluster]") {
    const std::vector<Eigen::Vector3f> pts = {{0.05f, 0.05f, 0.05f}, {0.35f, 0.05f, 0.05f},
                                              {0.15f, 0.05f, 0.05f}, {-0.05f, 0.05f, 0.05f},
                                              {0.25f, 0.25f, 0.25f}, {0.39f, 0.01f, 0.01f}};
    const auto v = cloud_analysis::voxelize(pts, 0.2);
    // Voxels: [0, 0.2)^3 holds points 0 and 2; [0.2, 0.4) x [0, 0.2)^2 points 1 and 5;
    // x in [-0.2, 0) point 3; [0.2, 0.4)^3 point 4.
    REQUIRE(v.centroid_m.size() == 4);
    CHECK(v.voxel_of == std::vector<std::uint32_t>{0, 1, 0, 2, 3, 1});
    CHECK(v.count == std::vector<std::uint32_t>{2, 2, 1, 1});
    CHECK(v.centroid_m[0].isApprox(Eigen::Vector3f(0.1f, 0.05f, 0.05f)));
    CHECK(v.centroid_m[1].isApprox(Eigen::Vector3f(0.37f, 0.03f, 0.03f)));
    CHECK(v.centroid_m[2].isApprox(pts[3]));
    CHECK(v.centroid_m[3].isApprox(pts[4]));
    // voxel_m <= 0: one voxel per point.
    const auto same = cloud_analysis::voxelize(pts, 0.0);
    CHECK(same.centroid_m.size() == pts.size());
    CHECK(same.voxel_of[5] == 5);
    CHECK(same.count == std::vector<std::uint32_t>(pts.size(), 1));
}

TEST_CASE("voxelize matches a naive reference on random walks and points on voxel faces",
          "[cluster]") {
    // Walks of small steps (runs of points in one voxel, as in pixel order), jumps, and points
    // on and next to voxel faces (where multiplying by the inverse size and dividing can
    // round to different cells); with one edge everywhere, and with the edge doubling at 15
    // and 25 m (walks cross those depths too).
    const double voxel_m = 0.4;
    for (const std::vector<double>& doubling : {std::vector<double>{}, {15.0, 25.0}}) {
        std::mt19937 rng(11);
        std::uniform_real_distribution<float> step(-0.05f, 0.05f), jump(-20.0f, 20.0f);
        std::uniform_int_distribution<int> face(-50, 50);
        std::vector<Eigen::Vector3f> pts;
        Eigen::Vector3f p(0.1f, 1.3f, 10.0f);
        for (int i = 0; i < 20000; ++i) {
            if (i % 500 == 0) p = Eigen::Vector3f(jump(rng), jump(rng), jump(rng) + 20.0f);
            p += Eigen::Vector3f(step(rng), step(rng), step(rng));
            pts.push_back(p);
            if (i % 7 == 0) {
                // Inside a voxel, then on its face and one float to either side of it.
                const auto on_face = static_cast<float>(face(rng) * voxel_m);
                for (const float x : {on_face - 0.01f, on_face, std::nextafter(on_face, -1e9f),
                                      std::nextafter(on_face, 1e9f), on_face + 0.01f, on_face}) {
                    pts.emplace_back(x, p.y(), p.z());
                }
            }
        }
        // Reference: band by depth, cells by division, voxels numbered by first point, sums
        // in point order.
        std::map<std::array<long long, 4>, std::uint32_t> id;
        std::vector<std::uint32_t> voxel_of;
        std::vector<Eigen::Vector3d> sums;
        std::vector<double> counts;
        for (const auto& q : pts) {
            long long band = 0;
            double edge = voxel_m;
            for (const double depth : doubling) {
                if (double{q.z()} >= depth) {
                    ++band;
                    edge *= 2.0;
                }
            }
            std::array<long long, 4> cell{band, 0, 0, 0};
            for (int a = 0; a < 3; ++a) {
                cell[static_cast<std::size_t>(a) + 1] =
                    static_cast<long long>(std::floor(double{q[a]} / edge));
            }
            const auto [it, inserted] = id.emplace(cell, static_cast<std::uint32_t>(sums.size()));
            if (inserted) {
                sums.emplace_back(Eigen::Vector3d::Zero());
                counts.push_back(0.0);
            }
            sums[it->second] += q.cast<double>();
            counts[it->second] += 1.0;
            voxel_of.push_back(it->second);
        }
        INFO(doubling.size() << " doubling depths");
        const auto v = cloud_analysis::voxelize(pts, voxel_m, doubling);
        CHECK(v.voxel_of == voxel_of);
        REQUIRE(v.centroid_m.size() == sums.size());
        for (std::size_t k = 0; k < sums.size(); ++k) {
            CHECK(v.centroid_m[k] == (sums[k] / counts[k]).cast<float>());
            CHECK(static_cast<double>(v.count[k]) == counts[k]);
        }
    }
}

TEST_CASE("voxelize refuses doubling depths out of order or too many", "[cluster]") {
    const std::vector<Eigen::Vector3f> pts = {{0.0f, 0.0f, 10.0f}};
    CHECK_THROWS_WITH(cloud_analysis::voxelize(pts, 0.4, {20.0, 10.0}),
                      Catch::Contains("ascending"));
    CHECK_THROWS_WITH(cloud_analysis::voxelize(pts, 0.4, std::vector<double>(8, 1.0)),
                      Catch::Contains("at most 7"));
}

TEST_CASE(
    "voxelize and clustering keep every voxel when there are more than their tables start with",
    "[cluster]") {
    // 120,000 points 0.3 m apart on a plane, each in its own 0.1 m voxel (more than the 65,536
    // voxels the voxel table starts with): one cluster at 0.5 m, none linked at 0.25 m.
    std::vector<Eigen::Vector3f> pts;
    for (int a = 0; a < 400; ++a) {
        for (int b = 0; b < 300; ++b) {
            pts.emplace_back(0.3f * static_cast<float>(a) - 60.0f, 1.5f,
                             0.3f * static_cast<float>(b) + 1.0f);
        }
    }
    const auto v = cloud_analysis::voxelize(pts, 0.1);
    REQUIRE(v.centroid_m.size() == pts.size());
    for (std::size_t i = 0; i < pts.size(); i += 997) {
        CHECK(v.voxel_of[i] == i);
        CHECK(v.centroid_m[i] == pts[i]);
    }
    ClusterOptions o;
    o.distance_at_10m_m = 0.5;
    o.growth = 0.0;
    o.distance_max_m = 0.5;
    const auto one = euclidean_clusters(v.centroid_m, o);
    REQUIRE(one.size() == 1);
    CHECK(one[0].size() == pts.size());
    o.distance_at_10m_m = 0.25;
    o.distance_max_m = 0.25;
    CHECK(euclidean_clusters(v.centroid_m, o).size() == pts.size());
}

TEST_CASE("a cap over 1000 times the distance at 10 m is refused, naming the field", "[cluster]") {
    ClusterOptions o;
    o.distance_at_10m_m = 0.01;
    o.distance_max_m = 10.0;
    CHECK_NOTHROW(o.validate());
    o.distance_max_m = 10.5;
    CHECK_THROWS_WITH(o.validate(), Catch::Contains("distance_max_m"));
}
