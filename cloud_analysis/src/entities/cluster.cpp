#include "cloud_analysis/entities/cluster.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <limits>
#include <stdexcept>

namespace cloud_analysis {
namespace {

/// Open-addressing hash map from a 64-bit key to a 32-bit value (linear probing, at most half
/// full; key and value side by side, so that a probe touches one cache line).
class CellTable {
  public:
    explicit CellTable(std::size_t expected) { resize(expected); }
    /// Value of key, inserting next_value when absent; `inserted` says which.
    std::uint32_t find_or_insert(std::uint64_t key, std::uint32_t next_value, bool& inserted) {
        if (2 * (size_ + 1) > slots_.size()) grow();
        for (std::size_t slot = hash(key) & mask_;; slot = (slot + 1) & mask_) {
            Slot& s = slots_[slot];
            if (s.key == key) {
                inserted = false;
                return s.value;
            }
            if (s.key == kEmpty) {
                s = Slot{key, next_value};
                ++size_;
                inserted = true;
                return next_value;
            }
        }
    }
    /// Index of key, or kNone.
    std::uint32_t find(std::uint64_t key) const {
        for (std::size_t slot = hash(key) & mask_;; slot = (slot + 1) & mask_) {
            const Slot& s = slots_[slot];
            if (s.key == key) return s.value;
            if (s.key == kEmpty) return kNone;
        }
    }
    static constexpr std::uint32_t kNone = std::numeric_limits<std::uint32_t>::max();

  private:
    static constexpr std::uint64_t kEmpty = std::numeric_limits<std::uint64_t>::max();
    struct Slot {
        std::uint64_t key = kEmpty;
        std::uint32_t value = 0;
    };
    void resize(std::size_t expected) {
        std::size_t slots = 64;
        while (slots < 2 * expected) slots *= 2;
        slots_.assign(slots, Slot{});
        mask_ = slots - 1;
        size_ = 0;
    }
    void grow() {
        const std::vector<Slot> old = std::move(slots_);
        resize(old.size());
        for (const Slot& s : old) {
            if (s.key == kEmpty) continue;
            bool inserted = false;
            find_or_insert(s.key, s.value, inserted);
        }
    }
    static std::size_t hash(std::uint64_t key) {
        key ^= key >> 33;
        key *= 0xff51afd7ed558ccdULL;
        key ^= key >> 33;
        return static_cast<std::size_t>(key);
    }
    std::vector<Slot> slots_;
    std::size_t mask_ = 0;
    std::size_t size_ = 0;
};

/// Key of cell (x, y, z) of grid level `level`: 4 bits of level, 3 x 20 bits of coordinates.
/// Coordinates wrap beyond +-2^19 cells; a wrapped cell only adds candidates, every link is
/// still decided by the distance test.
std::uint64_t cell_key(int level, std::int64_t x, std::int64_t y, std::int64_t z) {
    constexpr std::int64_t kMask = (1 << 20) - 1;
    return (static_cast<std::uint64_t>(level) << 60) |
           (static_cast<std::uint64_t>(x & kMask) << 40) |
           (static_cast<std::uint64_t>(y & kMask) << 20) | static_cast<std::uint64_t>(z & kMask);
}

/// floor(x) as an integer, without a call into libm (SSE2 has no rounding instruction);
/// clamped to +-4e15 (NaN gives 0), so any input is defined.
std::int64_t floor_int(double x) {
    if (!(x == x)) return 0;
    x = std::clamp(x, -4.0e15, 4.0e15);
    const auto t = static_cast<std::int64_t>(x);
    return x < static_cast<double>(t) ? t - 1 : t;
}

/// floor(x / size) with a multiplication by inverse = 1 / size; the division is made only
/// when the product lies within 1e-6 of an integer, where the two could round differently
/// (or beyond +-1e15, or NaN).
inline std::int64_t floor_div(double x, double size, double inverse) {
    const double q = x * inverse;
    if (q > -1.0e15 && q < 1.0e15) {
        const auto t = static_cast<std::int64_t>(q);
        const std::int64_t k = q < static_cast<double>(t) ? t - 1 : t;
        const double above = q - static_cast<double>(k);
        if (above > 1e-6 && above < 1.0 - 1e-6) return k;
    }
    return floor_int(x / size);
}

/// floor(x / 2^shift) for any sign.
std::int64_t floor_shift(std::int64_t x, int shift) {
    return x >= 0 ? x >> shift : -((-x - 1) >> shift) - 1;
}

/// Numbers of the occupied cells of the grid levels (cell (x, y, z) of level l covers base
/// cells x * 2^l ... x * 2^l + 2^l - 1 on each axis). A dense array over the base cells'
/// bounding box, one margin cell each side so that the 27 cells around any occupied one can be
/// asked for, when that array is small (a few bytes per point); else a hash table, so that
/// points spread over kilometres cost no more memory than their number.
class LevelCells {
  public:
    static constexpr std::uint32_t kNone = CellTable::kNone;

    /// For base cells base_cell[3 i .. 3 i + 2] of n points, levels 0 .. levels - 1.
    LevelCells(const std::vector<std::int64_t>& base_cell, std::size_t n, int levels) : hash_(0) {
        std::array<std::int64_t, 3> lo{}, hi{};
        for (int a = 0; a < 3; ++a) {
            lo[a] = n > 0 ? base_cell[static_cast<std::size_t>(a)] : 0;
            hi[a] = lo[a];
        }
        for (std::size_t i = 0; i < n; ++i) {
            for (int a = 0; a < 3; ++a) {
                lo[a] = std::min(lo[a], base_cell[3 * i + static_cast<std::size_t>(a)]);
                hi[a] = std::max(hi[a], base_cell[3 * i + static_cast<std::size_t>(a)]);
            }
        }
        // The cap keeps the array within 16 bytes per point (1 MiB at least).
        const std::uint64_t cap = std::max<std::uint64_t>(4 * std::uint64_t{n}, 1 << 18);
        std::uint64_t total = 0;
        for (int l = 0; l < levels && total <= cap; ++l) {
            Level& g = levels_[static_cast<std::size_t>(l)];
            g.offset = total;
            std::uint64_t cells = 1;
            for (int a = 0; a < 3 && cells <= cap; ++a) {
                g.lo[a] = floor_shift(lo[a], l) - 1;
                g.dim[a] = floor_shift(hi[a], l) + 2 - g.lo[a];
                const auto extent = static_cast<std::uint64_t>(g.dim[a]);
                cells = extent > cap / cells ? cap + 1 : cells * extent;
            }
            total += cells;
        }
        if (total <= cap) {
            dense_.assign(static_cast<std::size_t>(total), kNone);
        } else {
            hash_ = CellTable(n);
        }
    }
    /// Number of cell (x, y, z) of level l, given next_value when it had none; `inserted`
    /// says which.
    std::uint32_t find_or_insert(int l, std::int64_t x, std::int64_t y, std::int64_t z,
                                 std::uint32_t next_value, bool& inserted) {
        if (dense_.empty()) return hash_.find_or_insert(cell_key(l, x, y, z), next_value, inserted);
        std::uint32_t& id = dense_[index(l, x, y, z)];
        inserted = id == kNone;
        if (inserted) id = next_value;
        return id;
    }
    /// Calls f(number) for each occupied cell of the 27 around cell (x, y, z) of level l (in
    /// the dense array, (x, y, z) must lie within the base cells' bounding box), in the order of
    /// dx, dy, dz = -1, 0, 1 nested (dz innermost); in the dense array from the centre's index and
    /// fixed offsets.
    template <typename F>
    void for_each_near(int l, std::int64_t x, std::int64_t y, std::int64_t z, F&& f) const {
        if (dense_.empty()) {
            for (std::int64_t dx = -1; dx <= 1; ++dx) {
                for (std::int64_t dy = -1; dy <= 1; ++dy) {
                    for (std::int64_t dz = -1; dz <= 1; ++dz) {
                        const std::uint32_t c = hash_.find(cell_key(l, x + dx, y + dy, z + dz));
                        if (c != kNone) f(c);
                    }
                }
            }
            return;
        }
        const Level& g = levels_[static_cast<std::size_t>(l)];
        const auto sx = static_cast<std::ptrdiff_t>(g.dim[1] * g.dim[2]);
        const auto sy = static_cast<std::ptrdiff_t>(g.dim[2]);
        const std::uint32_t* centre = dense_.data() + index(l, x, y, z);
        for (std::ptrdiff_t dx = -sx; dx <= sx; dx += sx) {
            for (std::ptrdiff_t dy = -sy; dy <= sy; dy += sy) {
                for (std::ptrdiff_t dz = -1; dz <= 1; ++dz) {
                    const std::uint32_t c = centre[dx + dy + dz];
                    if (c != kNone) f(c);
                }
            }
        }
    }

  private:
    struct Level {
        std::array<std::int64_t, 3> lo{};
        std::array<std::int64_t, 3> dim{};
        std::uint64_t offset = 0;
    };
    std::size_t index(int l, std::int64_t x, std::int64_t y, std::int64_t z) const {
        const Level& g = levels_[static_cast<std::size_t>(l)];
        return static_cast<std::size_t>(
            g.offset + static_cast<std::uint64_t>(
                           ((x - g.lo[0]) * g.dim[1] + (y - g.lo[1])) * g.dim[2] + (z - g.lo[2])));
    }
    std::array<Level, 16> levels_{};
    std::vector<std::uint32_t> dense_;
    CellTable hash_;
};

/// Whether the horizontal offset d = q - p across the viewing ray through the midpoint of p
/// and q (camera at the origin, x right, z forward) is at most `cross_m`.
bool within_across_ray(const Eigen::Vector3f& p, const Eigen::Vector3f& q, const Eigen::Vector3f& d,
                       double cross_m) {
    const double mx = 0.5 * (double{p.x()} + double{q.x()});
    const double mz = 0.5 * (double{p.z()} + double{q.z()});
    const double norm2 = mx * mx + mz * mz;
    if (norm2 <= 0.0) return true;
    const double across = double{d.x()} * mz - double{d.z()} * mx;  // |d x ray| * |ray|
    return across * across <= cross_m * cross_m * norm2;
}

/// (z / 10 m)^exponent beyond 10 m, 1 nearer; the shipped exponents (0, 1 and 2) without a
/// call to pow (once per point).
double depth_growth(double z_m, double exponent) {
    if (!(z_m > 10.0) || exponent == 0.0) return 1.0;
    const double r = z_m / 10.0;
    return exponent == 1.0 ? r : exponent == 2.0 ? r * r : std::pow(r, exponent);
}

/// Each point's linking distance and its place on the hierarchical grid.
struct GridPlaces {
    int levels = 1;                       ///< levels of the grid
    std::vector<double> radius;           ///< per point: its linking distance, metres
    std::vector<std::int64_t> base_cell;  ///< per point: its cell (x, y, z) on level 0
    std::vector<std::uint8_t> level;      ///< per point: its level
};

/// Hierarchical grid (levels of cell size h0 * 2^l, nested): a point whose linking distance
/// is r sits in the finest level whose cell is at least r. Two points link within the
/// smaller of their distances, which is at most the cell size of the level of the point
/// that has it, so each neighbour of a point lies in the 27 cells around it on some level.
/// The cells are a little larger than the distances so that rounding cannot lose a link.
GridPlaces place_on_grid(const std::vector<Eigen::Vector3f>& points_m,
                         const ClusterOptions& options) {
    const std::size_t n = points_m.size();
    const double base_m = options.distance_at_10m_m;
    int levels = 1;
    while (base_m * static_cast<double>(1 << (levels - 1)) < options.distance_max_m) ++levels;
    const double cell0_m = base_m * (1.0 + 1e-5);
    std::vector<double> radius(n);
    std::vector<std::int64_t> base_cell(3 * n);
    std::vector<std::uint8_t> level(n);
    for (std::size_t i = 0; i < n; ++i) {
        radius[i] = options.distance_at(double{points_m[i].z()});
        int l = 0;
        while (l + 1 < levels && base_m * static_cast<double>(1 << l) < radius[i]) ++l;
        level[i] = static_cast<std::uint8_t>(l);
        for (int a = 0; a < 3; ++a)
            base_cell[3 * i + a] = floor_div(double{points_m[i][a]}, cell0_m, 1.0 / cell0_m);
    }
    return GridPlaces{levels, std::move(radius), std::move(base_cell), std::move(level)};
}

/// A point as the scan of its cell reads it: position, distances and index side by side.
struct Member {
    Eigen::Vector3f p;
    std::uint32_t point;
    double radius;
    double cross;  // distance across the ray, horizontally
};

/// Points of each cell, contiguous (cell_start), in index order; the unvisited ones first
/// (cell_left counts them) so that visited points leave the candidate lists.
struct CellMembers {
    std::vector<std::uint32_t> cell_of;     ///< per point: its cell
    std::vector<std::uint32_t> cell_start;  ///< per cell: its first slot, then the end
    std::vector<std::uint32_t> cell_left;   ///< per cell: its unvisited points
    std::vector<Member> members;            ///< per slot: the point in it
    std::vector<std::uint32_t> slot_of;     ///< per point: its slot
};

/// The points of each cell as records (position, distance, index) side by side, so that
/// scanning a cell reads one contiguous run of memory; cells numbered in `cells`.
CellMembers sort_into_cells(const std::vector<Eigen::Vector3f>& points_m, const GridPlaces& places,
                            const ClusterOptions& options, bool anisotropic, LevelCells& cells) {
    const std::size_t n = points_m.size();
    std::vector<std::uint32_t> cell_of(n);
    std::vector<std::uint32_t> cell_count;
    for (std::size_t i = 0; i < n; ++i) {
        const int l = places.level[i];
        const std::int64_t* b = &places.base_cell[3 * i];
        bool inserted = false;
        cell_of[i] = cells.find_or_insert(l, floor_shift(b[0], l), floor_shift(b[1], l),
                                          floor_shift(b[2], l),
                                          static_cast<std::uint32_t>(cell_count.size()), inserted);
        if (inserted) cell_count.push_back(0);
        ++cell_count[cell_of[i]];
    }
    std::vector<std::uint32_t> cell_start(cell_count.size() + 1, 0);
    for (std::size_t c = 0; c < cell_count.size(); ++c) {
        cell_start[c + 1] = cell_start[c] + cell_count[c];
    }
    std::vector<Member> members(n);
    std::vector<std::uint32_t> slot_of(n);
    std::vector<std::uint32_t> cell_left(cell_count.size(), 0);
    for (std::size_t i = 0; i < n; ++i) {
        const std::uint32_t c = cell_of[i];
        const std::uint32_t slot = cell_start[c] + cell_left[c]++;
        const double radius = places.radius[i];
        const double cross =
            anisotropic ? options.cross_distance_at(double{points_m[i].z()}) : radius;
        members[slot] = Member{points_m[i], static_cast<std::uint32_t>(i), radius, cross};
        slot_of[i] = slot;
    }
    return CellMembers{std::move(cell_of), std::move(cell_start), std::move(cell_left),
                       std::move(members), std::move(slot_of)};
}

/// Marks point i visited: the last unvisited point of its cell takes its slot.
inline void remove_unvisited(CellMembers& m, std::uint32_t i) {
    const std::uint32_t c = m.cell_of[i];
    const std::uint32_t last = m.cell_start[c] + --m.cell_left[c];
    const std::uint32_t at = m.slot_of[i];
    std::swap(m.members[at], m.members[last]);
    m.slot_of[m.members[at].point] = at;
    m.slot_of[i] = last;
}

/// Occupied cells around each base cell on every level, listed once per base cell: list id
/// holds cells[begin[id]] .. cells[end[id] - 1].
struct NearCells {
    LevelCells base_ids;  ///< list of each base cell
    std::vector<std::uint32_t> begin, end, cells;
};

/// List (in around) of the cells around point i's base cell, made when first asked for.
std::uint32_t cells_near(const GridPlaces& places, const LevelCells& cells, std::size_t i,
                         NearCells& around) {
    const std::int64_t* b = &places.base_cell[3 * i];
    bool inserted = false;
    const std::uint32_t id = around.base_ids.find_or_insert(
        0, b[0], b[1], b[2], static_cast<std::uint32_t>(around.begin.size()), inserted);
    if (inserted) {
        around.begin.push_back(static_cast<std::uint32_t>(around.cells.size()));
        for (int l = 0; l < places.levels; ++l) {
            cells.for_each_near(l, floor_shift(b[0], l), floor_shift(b[1], l), floor_shift(b[2], l),
                                [&](std::uint32_t c) { around.cells.push_back(c); });
        }
        around.end.push_back(static_cast<std::uint32_t>(around.cells.size()));
    }
    return id;
}

/// Region growing from each unvisited point in index order; a neighbour joins when closer
/// than the distance at the nearer depth, i.e. the smaller of the two points' distances.
/// The visiting order within a cluster depends on the grid; the clusters do not. Returns the
/// clusters of at least min_points points, in the order of their first point.
std::vector<std::vector<std::size_t>> grow_clusters(const std::vector<Eigen::Vector3f>& points_m,
                                                    const GridPlaces& places,
                                                    const LevelCells& cells, bool anisotropic,
                                                    std::size_t min_points, CellMembers& m,
                                                    NearCells& around) {
    const std::size_t n = points_m.size();
    std::vector<std::vector<std::size_t>> clusters;
    std::vector<char> visited(n, 0);
    std::vector<std::size_t> queue;
    for (std::size_t seed = 0; seed < n; ++seed) {
        if (visited[seed]) continue;
        visited[seed] = 1;
        remove_unvisited(m, static_cast<std::uint32_t>(seed));
        queue.assign(1, seed);
        for (std::size_t head = 0; head < queue.size(); ++head) {
            const std::size_t i = queue[head];
            const Eigen::Vector3f p = points_m[i];
            const double ri = places.radius[i];
            const double ci = m.members[m.slot_of[i]].cross;  // slot_of follows point i
            const std::uint32_t id = cells_near(places, cells, i, around);
            for (std::uint32_t k = around.begin[id]; k < around.end[id];) {
                const std::uint32_t c = around.cells[k];
                if (m.cell_left[c] == 0) {  // exhausted for good: drop it from the list
                    around.cells[k] = around.cells[--around.end[id]];
                    continue;
                }
                ++k;
                for (std::uint32_t slot = m.cell_start[c];
                     slot < m.cell_start[c] + m.cell_left[c];) {
                    const Member& mb = m.members[slot];
                    const double link = std::min(ri, mb.radius);
                    const Eigen::Vector3f d = mb.p - p;
                    if (double{d.squaredNorm()} > link * link ||
                        (anisotropic && !within_across_ray(p, mb.p, d, std::min(ci, mb.cross)))) {
                        ++slot;
                        continue;
                    }
                    const std::uint32_t j = mb.point;
                    visited[j] = 1;
                    remove_unvisited(m, j);  // moves another unvisited point into this slot
                    queue.push_back(j);
                }
            }
        }
        if (queue.size() >= min_points) clusters.push_back(queue);
    }
    return clusters;
}

/// The voxel grid of voxel_m <= 0: every point a voxel of its own.
void voxel_per_point(const std::vector<Eigen::Vector3f>& points_m, VoxelGrid& v) {
    const std::size_t n = points_m.size();
    v.centroid_m = points_m;
    v.count.assign(n, 1);
    for (std::size_t i = 0; i < n; ++i) v.voxel_of[i] = static_cast<std::uint32_t>(i);
}

/// Sums the points of each voxel (cells of edge[b], inverse[b] = 1 / edge[b], in depth band b:
/// b doubling depths at or below z), numbered in the order of their first points: returns the
/// sums, fills v.count with the voxels' points and v.voxel_of (sized) with each point's voxel.
std::vector<Eigen::Vector3d> sum_voxels(const std::vector<Eigen::Vector3f>& points_m,
                                        const std::vector<double>& doubling_depths_m,
                                        const std::vector<double>& edge,
                                        const std::vector<double>& inverse, VoxelGrid& v) {
    const std::size_t n = points_m.size();
    const auto band_of = [&](float z) {
        std::size_t b = 0;
        while (b < doubling_depths_m.size() && double{z} >= doubling_depths_m[b]) ++b;
        return b;
    };
    CellTable index(std::min<std::size_t>(n, 1 << 16));
    std::vector<Eigen::Vector3d> sums;
    std::vector<std::uint32_t>& counts = v.count;
    // Points arrive in pixel order, so runs of them share a voxel. A run's voxel (band, cells
    // cx, cy, cz) keeps its sum and count in registers until the run ends: the same additions
    // in the same order as into sums[last]. A point lies in the run's cell when it is in the
    // run's band and its scaled coordinate is more than 1e-6 inside the cell on every axis,
    // exactly where floor_div would return that cell without dividing.
    const auto inside = [](double q, std::int64_t c) {
        const double above = q - static_cast<double>(c);
        return above > 1e-6 && above < 1.0 - 1e-6;
    };
    const auto wrap = [](std::int64_t c) {
        return static_cast<std::uint64_t>(c + (1 << 19)) & 0xFFFFF;
    };
    std::int64_t cx = 0, cy = 0, cz = 0;
    std::size_t band = 0;
    std::uint64_t last_key = ~std::uint64_t{0};
    std::uint32_t last = 0;
    Eigen::Vector3d run_sum = Eigen::Vector3d::Zero();
    std::uint32_t run_count = 0;
    for (std::size_t i = 0; i < n; ++i) {
        const Eigen::Vector3f& p = points_m[i];
        const std::size_t b = band_of(p.z());
        const double inv = inverse[b];
        const double qx = double{p.x()} * inv, qy = double{p.y()} * inv, qz = double{p.z()} * inv;
        if (!(b == band && inside(qx, cx) && inside(qy, cy) && inside(qz, cz)) ||
            last_key == ~std::uint64_t{0}) {
            band = b;
            cx = floor_div(double{p.x()}, edge[b], inv);
            cy = floor_div(double{p.y()}, edge[b], inv);
            cz = floor_div(double{p.z()}, edge[b], inv);
            const std::uint64_t key =
                (std::uint64_t{b} << 60) | (wrap(cx) << 40) | (wrap(cy) << 20) | wrap(cz);
            if (key != last_key) {
                if (last_key != ~std::uint64_t{0}) {
                    sums[last] = run_sum;
                    counts[last] = run_count;
                }
                bool inserted = false;
                last = index.find_or_insert(key, static_cast<std::uint32_t>(sums.size()), inserted);
                if (inserted) {
                    sums.emplace_back(Eigen::Vector3d::Zero());
                    counts.push_back(0);
                }
                run_sum = sums[last];
                run_count = counts[last];
                last_key = key;
            }
        }
        run_sum += p.cast<double>();
        ++run_count;
        v.voxel_of[i] = last;
    }
    if (n > 0) {
        sums[last] = run_sum;
        counts[last] = run_count;
    }
    return sums;
}

}  // namespace

void ClusterOptions::validate() const {
    if (!(distance_at_10m_m > 0.0))
        throw std::invalid_argument("cluster.distance_at_10m_m: must be > 0");
    if (!(growth >= 0.0)) throw std::invalid_argument("cluster.growth: must be >= 0");
    if (!(distance_max_m >= distance_at_10m_m)) {
        throw std::invalid_argument("cluster.distance_max_m: must be >= distance_at_10m_m");
    }
    if (distance_max_m > 1000.0 * distance_at_10m_m) {
        throw std::invalid_argument("cluster.distance_max_m: must be <= 1000 * distance_at_10m_m");
    }
    if (min_points < 1) throw std::invalid_argument("cluster.min_points: must be >= 1");
    if (cross_growth && !(*cross_growth >= 0.0 && *cross_growth <= growth)) {
        throw std::invalid_argument("cluster.cross_growth: must be >= 0 and <= growth");
    }
    if (cross_distance_at_10m_m &&
        !(*cross_distance_at_10m_m > 0.0 && *cross_distance_at_10m_m <= distance_at_10m_m)) {
        throw std::invalid_argument(
            "cluster.cross_distance_at_10m_m: must be > 0 and <= distance_at_10m_m");
    }
}

double ClusterOptions::distance_at(double z_m) const {
    return std::min(distance_at_10m_m * depth_growth(z_m, growth), distance_max_m);
}

double ClusterOptions::cross_distance_at(double z_m) const {
    if (!cross_growth && !cross_distance_at_10m_m) return distance_at(z_m);
    return std::min(cross_distance_at_10m_m.value_or(distance_at_10m_m) *
                        depth_growth(z_m, cross_growth.value_or(growth)),
                    distance_at(z_m));
}

std::vector<std::vector<std::size_t>> euclidean_clusters(
    const std::vector<Eigen::Vector3f>& points_m, const ClusterOptions& options) {
    options.validate();
    const std::size_t n = points_m.size();
    if (n == 0) return {};
    if (n >= CellTable::kNone) throw std::invalid_argument("euclidean_clusters: too many points");
    const GridPlaces places = place_on_grid(points_m, options);
    LevelCells cells(places.base_cell, n, places.levels);
    const bool anisotropic =
        options.cross_growth.has_value() || options.cross_distance_at_10m_m.has_value();
    CellMembers members = sort_into_cells(points_m, places, options, anisotropic, cells);
    NearCells around{LevelCells(places.base_cell, n, 1), {}, {}, {}};
    std::vector<std::vector<std::size_t>> clusters =
        grow_clusters(points_m, places, cells, anisotropic, options.min_points, members, around);
    std::stable_sort(clusters.begin(), clusters.end(),
                     [](const auto& a, const auto& b) { return a.size() > b.size(); });
    return clusters;
}

VoxelGrid voxelize(const std::vector<Eigen::Vector3f>& points_m, double voxel_m,
                   const std::vector<double>& doubling_depths_m) {
    VoxelGrid v;
    const std::size_t n = points_m.size();
    if (n >= CellTable::kNone) throw std::invalid_argument("voxelize: too many points");
    if (doubling_depths_m.size() > 7) {
        throw std::invalid_argument("voxelize: at most 7 doubling depths");
    }
    if (!std::is_sorted(doubling_depths_m.begin(), doubling_depths_m.end())) {
        throw std::invalid_argument("voxelize: doubling depths must be ascending");
    }
    v.voxel_of.resize(n);
    if (voxel_m <= 0.0) {
        voxel_per_point(points_m, v);
        return v;
    }
    // Edge and its inverse per depth band (band b: b doubling depths at or below z).
    std::vector<double> edge(doubling_depths_m.size() + 1, voxel_m);
    for (std::size_t b = 1; b < edge.size(); ++b) edge[b] = 2.0 * edge[b - 1];
    std::vector<double> inverse(edge.size());
    for (std::size_t b = 0; b < edge.size(); ++b) inverse[b] = 1.0 / edge[b];
    const std::vector<Eigen::Vector3d> sums =
        sum_voxels(points_m, doubling_depths_m, edge, inverse, v);
    const std::vector<std::uint32_t>& counts = v.count;
    v.centroid_m.reserve(sums.size());
    for (std::size_t k = 0; k < sums.size(); ++k) {
        v.centroid_m.push_back((sums[k] / static_cast<double>(counts[k])).cast<float>());
    }
    return v;
}

}  // namespace cloud_analysis
