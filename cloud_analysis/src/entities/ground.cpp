#include "cloud_analysis/entities/ground.hpp"

#include <algorithm>
#include <cmath>
#include <random>
#include <stdexcept>

#include <Eigen/Eigenvalues>
#include <Eigen/Geometry>
#include "stereoscene/support/angles.hpp"

namespace cloud_analysis {
namespace {

using stereoscene::support::kPi;

/// Least-squares plane through points (smallest eigenvector of the covariance), normal up.
bool refine_plane(const std::vector<Eigen::Vector3d>& pts, Eigen::Vector3d& normal, double& d) {
    if (pts.size() < 3) return false;
    Eigen::Vector3d mean = Eigen::Vector3d::Zero();
    for (const auto& p : pts) mean += p;
    mean /= static_cast<double>(pts.size());
    Eigen::Matrix3d cov = Eigen::Matrix3d::Zero();
    for (const auto& p : pts) cov += (p - mean) * (p - mean).transpose();
    Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> solver(cov);
    normal = solver.eigenvectors().col(0).normalized();
    if (normal.y() > 0.0) normal = -normal;
    d = -normal.dot(mean);
    return true;
}

/// Points i in [begin, end) with |nx px[i] + ny py[i] + nz pz[i] + d| < tol. Also compiled for
/// AVX2, chosen at load time on CPUs that have it: the same operations on each point (no FMA
/// contraction), so the same count, four doubles at a time instead of two.
__attribute__((target_clones("avx2", "default"))) std::size_t count_near_plane(
    const double* px, const double* py, const double* pz, std::size_t begin, std::size_t end,
    double nx, double ny, double nz, double d, double tol) {
    std::size_t count = 0;
    for (std::size_t i = begin; i < end; ++i) {
        count += std::abs(nx * px[i] + ny * py[i] + nz * pz[i] + d) < tol ? 1 : 0;
    }
    return count;
}

}  // namespace

void GroundOptions::validate() const {
    if (!(inlier_distance_m > 0.0))
        throw std::invalid_argument("ground.inlier_distance_m: must be > 0");
    if (iterations < 1) throw std::invalid_argument("ground.iterations: must be >= 1");
    if (!(max_tilt_deg > 0.0 && max_tilt_deg < 90.0)) {
        throw std::invalid_argument("ground.max_tilt_deg: must be in (0, 90)");
    }
    if (!(max_range_m > 0.0)) throw std::invalid_argument("ground.max_range_m: must be > 0");
    if (max_samples < 3) throw std::invalid_argument("ground.max_samples: must be >= 3");
}

std::optional<GroundPlane> fit_ground_plane(const std::vector<Eigen::Vector3f>& points_m,
                                            const GroundOptions& options) {
    options.validate();
    std::vector<Eigen::Vector3d> pts;
    std::size_t eligible = 0;
    for (const auto& p : points_m) {
        if (p.z() > 0.0f && double{p.z()} < options.max_range_m) ++eligible;
    }
    const std::size_t stride =
        eligible > options.max_samples ? eligible / options.max_samples + 1 : 1;
    std::size_t k = 0;
    for (const auto& p : points_m) {
        if (!(p.z() > 0.0f && double{p.z()} < options.max_range_m)) continue;
        if (k++ % stride == 0) pts.push_back(p.cast<double>());
    }
    if (pts.size() < 3 || pts.size() < std::min<std::size_t>(options.min_inliers, 3)) {
        return std::nullopt;
    }
    std::vector<double> px(pts.size()), py(pts.size()), pz(pts.size());
    for (std::size_t i = 0; i < pts.size(); ++i) {
        px[i] = pts[i].x();
        py[i] = pts[i].y();
        pz[i] = pts[i].z();
    }
    constexpr std::size_t kBlock = 1024;
    const double cos_max_tilt = std::cos(options.max_tilt_deg * kPi / 180.0);
    std::mt19937 rng(options.seed);
    std::uniform_int_distribution<std::size_t> pick(0, pts.size() - 1);
    std::size_t best_count = 0;
    Eigen::Vector3d best_n(0.0, -1.0, 0.0);
    double best_d = 0.0;
    for (int it = 0; it < options.iterations; ++it) {
        const auto& a = pts[pick(rng)];
        const auto& b = pts[pick(rng)];
        const auto& c = pts[pick(rng)];
        Eigen::Vector3d n = (b - a).cross(c - a);
        const double norm = n.norm();
        if (norm < 1e-9) continue;
        n /= norm;
        if (n.y() > 0.0) n = -n;
        if (-n.y() < cos_max_tilt) continue;
        const double d = -n.dot(a);
        // Counted in blocks (vectorised over px/py/pz); a hypothesis that can no longer beat
        // the best one stops early.
        const double nx = n.x(), ny = n.y(), nz = n.z(), tol = options.inlier_distance_m;
        std::size_t count = 0;
        for (std::size_t begin = 0; begin < pts.size(); begin += kBlock) {
            if (count + (pts.size() - begin) <= best_count) break;
            const std::size_t end = std::min(pts.size(), begin + kBlock);
            count +=
                count_near_plane(px.data(), py.data(), pz.data(), begin, end, nx, ny, nz, d, tol);
        }
        if (count > best_count) {
            best_count = count;
            best_n = n;
            best_d = d;
        }
    }
    // Two least-squares refinements on the inliers of the current plane.
    for (int round = 0; round < 2 && best_count >= 3; ++round) {
        std::vector<Eigen::Vector3d> inliers;
        for (const auto& p : pts) {
            if (std::abs(best_n.dot(p) + best_d) < options.inlier_distance_m) inliers.push_back(p);
        }
        Eigen::Vector3d n;
        double d = 0.0;
        if (!refine_plane(inliers, n, d) || -n.y() < cos_max_tilt) break;
        best_n = n;
        best_d = d;
        best_count = inliers.size();
    }
    // Inliers among the sample, scaled back to the full cloud.
    const std::size_t inliers_full = best_count * stride;
    if (best_count < 3 || inliers_full < options.min_inliers) return std::nullopt;
    GroundPlane plane;
    plane.normal = best_n;
    plane.d = best_d;
    plane.inliers = inliers_full;
    return plane;
}

}  // namespace cloud_analysis
