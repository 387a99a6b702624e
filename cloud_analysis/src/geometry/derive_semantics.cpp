#include <algorithm>
#include <array>
#include <cmath>
#include <numeric>
#include <stdexcept>
#include <tuple>
#include <unordered_map>
#include <utility>
#include <vector>

#include "cloud_analysis/entities/cluster.hpp"
#include "cloud_analysis/geometry/scene_geometry.hpp"

namespace cloud_analysis::geometry {
namespace {

/// Palette indices of the classes the rules decide (kVoidClass when the palette lacks one).
struct Classes {
    std::uint16_t road, sidewalk, terrain, car, person, pole, vegetation, building, wall, sky,
        other;
    explicit Classes(const Palette& p)
        : road(find_class(p, "road")),
          sidewalk(find_class(p, "sidewalk")),
          terrain(find_class(p, "terrain")),
          car(find_class(p, "car")),
          person(find_class(p, "person")),
          pole(find_class(p, "pole")),
          vegetation(find_class(p, "vegetation")),
          building(find_class(p, "building")),
          wall(find_class(p, "wall") != kVoidClass ? find_class(p, "wall")
                                                   : find_class(p, "building")),
          sky(find_class(p, "sky")),
          other(find_class(p, "static")) {}
};

/// One u-disparity cell: the obstacle pixels of a column band at one disparity, in one of two
/// layers: below layer_height_m (where cars are) or above it (crowns, walls' upper floors).
struct Cell {
    int count = 0;          ///< obstacle pixels at or above low_cut_m
    float height_sum = 0;   ///< sum of their heights above the road, metres
    double d_sum = 0.0;     ///< sum of their disparities, px
    int green = 0;          ///< of them green
    int at_cut = 0;         ///< of them within continuity_band_m of the layers' border
    float top1 = -1e9f;     ///< highest height above the road, metres
    float top2 = -1e9f;     ///< second highest (robust top)
    float blend1 = -1e9f;   ///< the same two over its pixels on a blend (on_blend) or at the
    float blend2 = -1e9f;   ///< foot of a surface above (foot_of_surface_above), which give
                            ///< its top only when it has no other
    float low = 1e9f;       ///< lowest height, metres
    float high = -1e9f;     ///< highest height, metres
    int top_v = 1 << 30;    ///< row of its highest pixel (smallest v)
    int top_u = 0;          ///< column of that pixel
    bool occluded = false;  ///< a nearer surface lies right above that pixel: top unknown
    int segment = -1;       ///< segment index once linked; -1: sparse (noise)
    bool is_tall = false;   ///< upper layer, or a lower layer the surface above continues
    std::array<int, 2> surface{-1, -1};  ///< lower layer: the tall cells one disparity bin
                                         ///< nearer and farther whose surface it may hold
                                         ///< (GeometryOptions::split_surface_px), -1: none
};

/// Cells per (column band, disparity bin): the lower and the upper layer.
constexpr int kLayers = 2;

/// Heights within this of a tall cell's are its surface's (GeometryOptions::split_surface_px):
/// one image row spans 0.04 m at 30 m, metres.
constexpr float kSplitSurfaceMarginM = 0.05f;

/// Whether heights lo to hi lie within tall cell t's (kSplitSurfaceMarginM).
bool within_heights(const Cell& t, float lo, float hi) {
    return lo >= t.low - kSplitSurfaceMarginM && hi <= t.high + kSplitSurfaceMarginM;
}

/// The rig's depth of disparity d and the pixel grid, shared by the passes.
struct Rig {
    double fb = 0.0, offset = 0.0, cx = 0.0, cy = 0.0, fx = 0.0, fy = 0.0;
    explicit Rig(const StereoCamera& c)
        : fb(c.fx_px * c.baseline_m),
          offset(c.cx_px - c.cx_right_px),
          cx(c.cx_px),
          cy(c.cy_px),
          fx(c.fx_px),
          fy(c.fy_px) {}
};

/// The u-disparity grid and each pixel's place in it.
struct Grid {
    int bins_u = 0, bins_d = 0;
    std::vector<int> bin_of_tenth;   ///< disparity bin of floor(10 d)
    std::vector<double> bin_centre;  ///< disparity at the centre of each bin, px
    std::vector<Cell> cells;
    std::vector<std::int32_t> pixel_cell;  ///< per pixel: its cell, -1 when none
    std::vector<char> pixel_low;           ///< per pixel: below low_cut_m
    std::vector<char> pixel_green;         ///< per pixel: green (green_mask)
    std::vector<float> pixel_height;       ///< per pixel in a cell: height above the road, m
};

int find_root(std::vector<int>& parent, int i) {
    while (parent[i] != i) {
        parent[i] = parent[parent[i]];
        i = parent[i];
    }
    return i;
}

void unite(std::vector<int>& parent, int a, int b) {
    a = find_root(parent, a);
    b = find_root(parent, b);
    if (a != b) parent[std::max(a, b)] = std::min(a, b);
}

bool is_green(int r, int g, int b) { return g >= r + 6 && g * 10 >= r * 11 && g * 10 >= b * 11; }

/// Per pixel: whether the mean colour of its (2 radius + 1)^2 window is green (foliage's own
/// shadows between sunlit leaves are green only on average); all 0 without a colour image.
std::vector<char> green_mask(const ImageU8& left, int w, int h, int radius) {
    std::vector<char> mask(static_cast<std::size_t>(w) * h, 0);
    if (left.channels != 3 || left.empty() || left.width_px != w || left.height_px != h) {
        return mask;
    }
    // Integral image of the three channels, (w + 1) x (h + 1).
    const std::size_t stride = static_cast<std::size_t>(w) + 1;
    std::vector<std::array<std::int64_t, 3>> sum(stride * (h + 1), {0, 0, 0});
    for (int v = 0; v < h; ++v) {
        std::array<std::int64_t, 3> row{0, 0, 0};
        for (int u = 0; u < w; ++u) {
            const std::uint8_t* p = left.at(u, v);
            for (int c = 0; c < 3; ++c) {
                row[c] += p[c];
                sum[(v + 1) * stride + u + 1][c] = sum[v * stride + u + 1][c] + row[c];
            }
        }
    }
    for (int v = 0; v < h; ++v) {
        const int v0 = std::max(0, v - radius), v1 = std::min(h, v + radius + 1);
        for (int u = 0; u < w; ++u) {
            const int u0 = std::max(0, u - radius), u1 = std::min(w, u + radius + 1);
            std::array<std::int64_t, 3> m{};
            for (int c = 0; c < 3; ++c) {
                m[c] = sum[v1 * stride + u1][c] - sum[v0 * stride + u1][c] -
                       sum[v1 * stride + u0][c] + sum[v0 * stride + u0][c];
            }
            const std::int64_t n = static_cast<std::int64_t>(v1 - v0) * (u1 - u0);
            mask[static_cast<std::size_t>(v) * w + u] = is_green(
                static_cast<int>(m[0] / n), static_cast<int>(m[1] / n), static_cast<int>(m[2] / n));
        }
    }
    return mask;
}

double quantile(std::vector<float>& v, double q) {
    if (v.empty()) return 0.0;
    const std::size_t k = std::min(v.size() - 1, static_cast<std::size_t>(q * (v.size() - 1)));
    std::nth_element(v.begin(), v.begin() + static_cast<std::ptrdiff_t>(k), v.end());
    return double{v[k]};
}

/// Extents of a weighted footprint (x, z, weight) along its main axis and across it (2-98 %),
/// metres.
std::pair<double, double> footprint_extents(const std::vector<Eigen::Vector3d>& pts) {
    double wsum = 0.0;
    Eigen::Vector2d mean = Eigen::Vector2d::Zero();
    for (const auto& p : pts) {
        mean += p.z() * p.head<2>();
        wsum += p.z();
    }
    if (wsum <= 0.0) return {0.0, 0.0};
    mean /= wsum;
    Eigen::Matrix2d cov = Eigen::Matrix2d::Zero();
    for (const auto& p : pts) {
        const Eigen::Vector2d q = p.head<2>() - mean;
        cov += p.z() * q * q.transpose();
    }
    const double tr = cov.trace(), det = cov(0, 0) * cov(1, 1) - cov(0, 1) * cov(1, 0);
    const double l1 = tr / 2.0 + std::sqrt(std::max(0.0, tr * tr / 4.0 - det));
    Eigen::Vector2d axis(cov(0, 1), l1 - cov(0, 0));
    if (axis.norm() < 1e-12) {
        axis = cov(0, 0) >= cov(1, 1) ? Eigen::Vector2d(1, 0) : Eigen::Vector2d(0, 1);
    }
    axis.normalize();
    const Eigen::Vector2d normal(-axis.y(), axis.x());
    std::vector<float> along, across;
    along.reserve(pts.size());
    across.reserve(pts.size());
    for (const auto& p : pts) {
        along.push_back(static_cast<float>(axis.dot(p.head<2>() - mean)));
        across.push_back(static_cast<float>(normal.dot(p.head<2>() - mean)));
    }
    const double length = quantile(along, 0.98) - quantile(along, 0.02);
    return {length, quantile(across, 0.98) - quantile(across, 0.02)};
}

/// Whether pixel (u, v) lies on the matcher's blend between a nearer surface above and a
/// farther one below (a tree's crown in front of a bus's side): its disparity is below the
/// column's `rows` rows above and above the column's `rows` rows below, each by more than
/// `step_px`. Above the road such a ramp is no surface's own (a face is level in its column; a
/// bonnet, a roof or the road below the camera run the other way), only under an overhang.
bool on_blend(const DisparityMap& disparity, int u, int v, int rows, double step_px) {
    const int w = disparity.width_px;
    if (v < rows || v + rows >= disparity.height_px) return false;
    const double above = disparity.disparity_px[static_cast<std::size_t>(v - rows) * w + u];
    const double here = disparity.disparity_px[static_cast<std::size_t>(v) * w + u];
    const double below = disparity.disparity_px[static_cast<std::size_t>(v + rows) * w + u];
    return above > 0.0 && below > 0.0 && above - here > step_px && here - below > step_px;
}

/// Whether lower-layer pixel (u, v), of disparity d, is the foot of a surface in the upper
/// layer: its column runs up into that layer within `rows` rows, each step of disparity smaller
/// than `step_px` (the lowest rows of a tree's crown hanging just under the layers' border).
bool foot_of_surface_above(const DisparityMap& disparity, const std::vector<std::int32_t>& cell_of,
                           double offset, int u, int v, double d, int rows, double step_px) {
    const int w = disparity.width_px;
    double previous = d;
    for (int k = 1; k <= rows && v - k >= 0; ++k) {
        const std::size_t q = static_cast<std::size_t>(v - k) * w + u;
        const double above = double{disparity.disparity_px[q]} - offset;
        if (!(above > 0.0) || std::abs(above - previous) >= step_px) return false;
        if (cell_of[q] >= 0 && cell_of[q] % kLayers == 1) return true;
        previous = above;
    }
    return false;
}

/// Disparity bins 1 px wide, widening to `share` of the disparity near the camera (where 1 px
/// is a few centimetres of depth and an oblique surface would scatter over many bins).
void make_bins(double max_d, double share, Grid& g) {
    const auto tenths = static_cast<std::size_t>(std::max(0.0, max_d) * 10.0) + 2;
    g.bin_of_tenth.resize(tenths);
    g.bin_centre.clear();
    double start = 0.0;
    std::size_t t = 0;
    while (t < tenths) {
        const double width = std::max(1.0, share * start);
        const double end = start + width;
        const int bin = static_cast<int>(g.bin_centre.size());
        for (; t < tenths && static_cast<double>(t) < end * 10.0; ++t) g.bin_of_tenth[t] = bin;
        g.bin_centre.push_back(start + width / 2.0);
        start = end;
    }
    g.bins_d = static_cast<int>(g.bin_centre.size());
}

/// Fewest pixels of a dense cell at disparity bin bd, and the pixels within continuity_band_m
/// of the layers' border that make a surface continue across it.
std::pair<int, double> cell_thresholds(const Grid& g, const Rig& rig, const GeometryOptions& o,
                                       int bd) {
    // Pixels a surface h metres tall fills in a cell at this disparity.
    const double px_per_m =
        rig.fy * g.bin_centre[static_cast<std::size_t>(bd)] / rig.fb * o.column_bin_px;
    return {std::max(o.min_cell_pixels, static_cast<int>(o.min_cell_height_m * px_per_m)),
            o.continuity_share * o.continuity_band_m * px_per_m};
}

/// Every cell's kind: tall in the upper layer, and in the lower layer when its surface runs on
/// across the layers' border (a wall, a trunk: then both layers join when linked). A car under
/// a tree's crown has a gap there, so its cells stay low and apart from the crown's. A tall
/// surface at the border between two disparity bins (the matcher's sub-pixel steps put its
/// rows in either) leaves part of its lower rows in the next bin, in a cell of their own that
/// does not reach the border: the cell is that surface's when its mean disparity lies within
/// split_surface_px of a dense, tall, not green lower cell of its column band one bin away and
/// its heights lie within that cell's (a tree's trunk or crown, green, often stands just
/// before a car; a car before a wall hides the wall's foot, so its cell reaches lower).
void mark_kinds(Grid& g, const Rig& rig, const GeometryOptions& o) {
    const auto index = [&g](int bu, int bd, int layer) {
        return static_cast<std::size_t>((bu * g.bins_d + bd) * kLayers + layer);
    };
    std::vector<char> dense_tall(g.cells.size(), 0);  // dense, tall by continuity, not green
    for (int bd = 0; bd < g.bins_d; ++bd) {
        const auto [min_count, at_cut] = cell_thresholds(g, rig, o, bd);
        for (int bu = 0; bu < g.bins_u; ++bu) {
            Cell& lower = g.cells[index(bu, bd, 0)];
            g.cells[index(bu, bd, 1)].is_tall = true;
            int upper_at_cut = 0;  // the border rows of the surface above, noise spread over bins
            for (int k = std::max(0, bd - 1); k <= std::min(g.bins_d - 1, bd + 1); ++k) {
                upper_at_cut += g.cells[index(bu, k, 1)].at_cut;
            }
            lower.is_tall = lower.at_cut >= at_cut && upper_at_cut >= at_cut;
            dense_tall[index(bu, bd, 0)] =
                lower.is_tall && lower.count >= min_count &&
                static_cast<double>(lower.green) < o.green_fraction * lower.count;
        }
    }
    if (!(o.split_surface_px > 0.0)) return;
    for (int bu = 0; bu < g.bins_u; ++bu) {
        for (int bd = 0; bd < g.bins_d; ++bd) {
            Cell& c = g.cells[index(bu, bd, 0)];
            if (c.is_tall || c.count == 0) continue;
            bool inside = false;
            for (int side = 0; side < 2; ++side) {
                const int nd = bd + (side == 0 ? -1 : 1);
                if (nd < 0 || nd >= g.bins_d || !dense_tall[index(bu, nd, 0)]) continue;
                const Cell& t = g.cells[index(bu, nd, 0)];
                if (std::abs(c.d_sum / c.count - t.d_sum / t.count) > o.split_surface_px) continue;
                c.surface[static_cast<std::size_t>(side)] = static_cast<int>(index(bu, nd, 0));
                inside = inside || within_heights(t, c.low, c.high);
            }
            c.is_tall = inside;
        }
    }
}

/// Pass 1: road pixels labelled, every other pixel above the road counted in its cell; then the
/// cells' kinds (mark_kinds) and their tops.
Grid fill_grid(const DisparityMap& disparity, const Rig& rig, const ImageU8& left,
               const GroundEstimate& ground, const GeometryOptions& o, std::uint16_t road,
               ClassImage& out) {
    const int w = disparity.width_px, h = disparity.height_px;
    double max_d = 0.0;
    for (const float d : disparity.disparity_px) max_d = std::max(max_d, double{d} - rig.offset);
    Grid g;
    g.bins_u = (w + o.column_bin_px - 1) / o.column_bin_px;
    make_bins(max_d, o.disparity_bin_share, g);
    g.cells.resize(static_cast<std::size_t>(g.bins_u) * g.bins_d * kLayers);
    g.pixel_cell.assign(static_cast<std::size_t>(w) * h, -1);
    g.pixel_low.assign(g.pixel_cell.size(), 0);
    g.pixel_green.assign(g.pixel_cell.size(), 0);
    g.pixel_height.assign(g.pixel_cell.size(), 0.0f);
    const Eigen::Vector3d n = ground.plane.normal;
    const double plane_d = ground.plane.d;
    const double min_d = rig.fb / o.max_depth_m;
    // Height error of a road point at depth z for a disparity error e: h_cam * z * e / (f B).
    const double slope = o.disparity_noise_px * plane_d / rig.fb;
    const auto tall_m = static_cast<float>(o.layer_height_m);
    const auto band_m = static_cast<float>(o.continuity_band_m);
    const std::vector<char> green_px = green_mask(left, w, h, o.green_window_px);
    std::vector<std::size_t> lower_at_cut;  // lower-layer pixels near the layers' border
    for (int v = 0; v < h; ++v) {
        const std::size_t row = static_cast<std::size_t>(v) * w;
        const double row_term = n.y() * (v - rig.cy) / rig.fy + n.z();
        for (int u = 0; u < w; ++u) {
            const double raw = double{disparity.disparity_px[row + u]};
            const double d = raw - rig.offset;
            if (!(raw > 0.0) || !(d > min_d)) continue;
            const double z = rig.fb / d;
            const double height = (n.x() * (u - rig.cx) / rig.fx + row_term) * z + plane_d;
            const double tolerance = o.ground_tolerance_m + slope * z;
            if (height < -std::max(0.5, 3.0 * tolerance)) continue;  // under the road: mismatch
            if (height <= tolerance) {
                out.class_index[row + u] = road;
                continue;
            }
            const float hf = static_cast<float>(std::min(height, o.max_obstacle_height_m));
            const int upper = hf > tall_m ? 1 : 0;
            const int cell = ((u / o.column_bin_px) * g.bins_d +
                              g.bin_of_tenth[static_cast<std::size_t>(d * 10.0)]) *
                                 kLayers +
                             upper;
            g.pixel_cell[row + u] = cell;
            const bool green = green_px[row + u] != 0;
            g.pixel_green[row + u] = green ? 1 : 0;
            if (height < o.low_cut_m) {
                g.pixel_low[row + u] = 1;
                continue;
            }
            Cell& c = g.cells[static_cast<std::size_t>(cell)];
            ++c.count;
            c.d_sum += d;
            g.pixel_height[row + u] = hf;
            c.height_sum += hf;
            if (std::abs(hf - tall_m) <= band_m) {
                if (upper || !(o.continuity_behind_m > 0.0)) {
                    ++c.at_cut;
                } else {
                    lower_at_cut.push_back(row + u);
                }
            }
            c.green += green ? 1 : 0;
            c.low = std::min(c.low, hf);
            c.high = std::max(c.high, hf);
        }
    }
    // A lower cell's border rows continue its own surface only at its depth: at range one bin
    // spans metres, and the surface seen over a thing's top (a bus's back 1 m beyond a car's
    // roof at 30 m) shares its cell, pixel-locked a few tenths of a pixel farther. A surface
    // along the ray spreads over the whole bin, so only pixels farther than both limits drop.
    for (const std::size_t p : lower_at_cut) {
        Cell& c = g.cells[static_cast<std::size_t>(g.pixel_cell[p])];
        const double d = double{disparity.disparity_px[p]} - rig.offset;
        const double mean_d = c.d_sum / c.count;
        if (d >= mean_d - o.continuity_behind_px ||
            rig.fb / d <= rig.fb / mean_d + o.continuity_behind_m) {
            ++c.at_cut;
        }
    }
    mark_kinds(g, rig, o);
    // Whether lower-layer pixel height hf of cell c lies within a tall cell whose surface c
    // holds in part: that surface's pixels, not c's own.
    const auto on_split_surface = [&g](const Cell& c, float hf) {
        return std::any_of(c.surface.begin(), c.surface.end(), [&](int j) {
            return j >= 0 && within_heights(g.cells[static_cast<std::size_t>(j)], hf, hf);
        });
    };
    // Tops second, from the pixels at the cell's depth: at range one disparity bin spans
    // metres, and the surface just behind a thing (a bus's side above a car's roof, 1-2 px of
    // disparity farther) shares its bins but not its top, nor does the lowest edge of a tree's
    // crown a metre in front of a car's end, which runs on up into the upper layer. Pixels on
    // a blend (on_blend) or at the foot of a surface above, ahead of the cell's mean, count
    // only in cells that have no other.
    const auto raise = [](float hf, float& top, float& second) {
        if (hf > top) {
            second = top;
            top = hf;
        } else if (hf > second) {
            second = hf;
        }
    };
    for (int v = 0; v < h; ++v) {
        const std::size_t row = static_cast<std::size_t>(v) * w;
        for (int u = 0; u < w; ++u) {
            const std::int32_t cell = g.pixel_cell[row + u];
            if (cell < 0 || g.pixel_low[row + u]) continue;
            Cell& c = g.cells[static_cast<std::size_t>(cell)];
            const double d = double{disparity.disparity_px[row + u]} - rig.offset;
            const double mean_d = c.d_sum / c.count;
            if (d < mean_d - o.top_behind_px) continue;
            const float hf = g.pixel_height[row + u];
            if (hf > c.top2 || hf > c.blend2) {  // else neither pair changes
                if ((!c.is_tall && on_split_surface(c, hf)) ||
                    on_blend(disparity, u, v, o.blend_rows, o.blend_step_px) ||
                    (d > mean_d + o.foot_ahead_px &&
                     foot_of_surface_above(disparity, g.pixel_cell, rig.offset, u, v, d,
                                           o.blend_rows, o.blend_step_px))) {
                    raise(hf, c.blend1, c.blend2);
                } else {
                    raise(hf, c.top1, c.top2);
                }
            }
            if (v < c.top_v) {
                c.top_v = v;
                c.top_u = u;
            }
        }
    }
    for (Cell& c : g.cells) {
        if (c.top1 < -1e8f) {
            c.top1 = c.blend1;
            c.top2 = c.blend2;
        }
    }
    return g;
}

/// Whether the first disparity above a cell's highest pixel (within a few rows) is nearer: then
/// an occluder (a tree's crown over a wall's foot) hides the cell's real top.
bool top_occluded(const DisparityMap& disparity, const Cell& c, double cell_d) {
    const int w = disparity.width_px;
    for (int v = c.top_v - 1; v >= std::max(0, c.top_v - 6); --v) {
        const double d = double{disparity.disparity_px[static_cast<std::size_t>(v) * w + c.top_u]};
        if (!(d > 0.0)) continue;
        return d > cell_d * 1.15 + 1.0;
    }
    return false;
}

/// Pass 2a: the dense cells, each its own root (-1 for sparse cells), and whether a nearer
/// surface hides each one's top.
std::vector<int> dense_cells(Grid& g, const DisparityMap& disparity, const Rig& rig,
                             const GeometryOptions& o) {
    std::vector<int> parent(g.cells.size(), -1);
    for (int bd = 0; bd < g.bins_d; ++bd) {
        const int min_count = cell_thresholds(g, rig, o, bd).first;
        for (int bu = 0; bu < g.bins_u; ++bu) {
            for (int layer = 0; layer < kLayers; ++layer) {
                const int i = (bu * g.bins_d + bd) * kLayers + layer;
                Cell& c = g.cells[static_cast<std::size_t>(i)];
                if (c.count < min_count) continue;
                parent[static_cast<std::size_t>(i)] = i;
                c.occluded = top_occluded(disparity, c, g.bin_centre[static_cast<std::size_t>(bd)]);
            }
        }
    }
    return parent;
}

/// Pass 2b: each dense cell (dense_cells) linked to the dense cells of the same kind in the next
/// two column bands within link_depth_m; returns each dense cell's root (-1 for sparse cells).
std::vector<int> link_cells(Grid& g, const DisparityMap& disparity, const Rig& rig,
                            const GeometryOptions& o) {
    std::vector<int> parent = dense_cells(g, disparity, rig, o);
    for (int bu = 0; bu < g.bins_u; ++bu) {
        for (int bd = 0; bd < g.bins_d; ++bd) {
            const double dd = g.bin_centre[static_cast<std::size_t>(bd)];
            const double bin_width = std::max(1.0, o.disparity_bin_share * dd);
            const int reach = std::clamp(
                static_cast<int>(std::ceil(o.link_depth_m * dd * dd / rig.fb / bin_width)), 1, 6);
            for (int layer = 0; layer < kLayers; ++layer) {
                const int i = (bu * g.bins_d + bd) * kLayers + layer;
                if (parent[static_cast<std::size_t>(i)] < 0) continue;
                const bool tall = g.cells[static_cast<std::size_t>(i)].is_tall;
                for (int du = 0; du <= 2 && bu + du < g.bins_u; ++du) {
                    for (int k = -reach; k <= reach; ++k) {
                        const int nd = bd + k;
                        if (nd < 0 || nd >= g.bins_d) continue;
                        for (int nl = 0; nl < kLayers; ++nl) {
                            const int j = ((bu + du) * g.bins_d + nd) * kLayers + nl;
                            if (j <= i && du == 0) continue;
                            if (parent[static_cast<std::size_t>(j)] >= 0 &&
                                g.cells[static_cast<std::size_t>(j)].is_tall == tall) {
                                unite(parent, i, j);
                            }
                        }
                    }
                }
            }
        }
    }
    return parent;
}

/// The alternative to link_cells (GeometryOptions::segmentation "clusters"): the dense cells,
/// as 3D points (x, mean height, z), grouped by Euclidean clustering with the
/// extractor's depth-grown distance, whatever their kind (docs/entities.md compares the two).
std::vector<int> cluster_cells(Grid& g, const DisparityMap& disparity, const Rig& rig,
                               const GeometryOptions& o) {
    const std::vector<int> dense = dense_cells(g, disparity, rig, o);
    std::vector<Eigen::Vector3f> centres;
    std::vector<int> ids;
    for (int i = 0; i < static_cast<int>(g.cells.size()); ++i) {
        if (dense[static_cast<std::size_t>(i)] < 0) continue;
        const Cell& c = g.cells[static_cast<std::size_t>(i)];
        const int column_bin = i / kLayers;
        const double z = rig.fb / g.bin_centre[static_cast<std::size_t>(column_bin % g.bins_d)];
        const double u = ((column_bin / g.bins_d) + 0.5) * o.column_bin_px;
        centres.emplace_back(static_cast<float>((u - rig.cx) * z / rig.fx),
                             c.height_sum / static_cast<float>(c.count), static_cast<float>(z));
        ids.push_back(i);
    }
    ClusterOptions co;
    co.distance_at_10m_m = o.cluster_distance_m;
    co.growth = 1.0;
    co.distance_max_m = 4.0 * o.cluster_distance_m;
    std::vector<int> parent(g.cells.size(), -1);
    for (const auto& cluster : euclidean_clusters(centres, co)) {
        const int root = ids[cluster.front()];
        for (const std::size_t k : cluster) parent[static_cast<std::size_t>(ids[k])] = root;
    }
    return parent;
}

/// Statistics of one linked segment, gathered from its cells.
struct SegmentStats {
    std::size_t pixels = 0, green = 0, occluded = 0, tall_pixels = 0;
    std::size_t border_pixels = 0;  ///< in cells within kEdgeColumns of the matcher's left
                                    ///< border at their depth, or left of it
    bool tall = false;
    bool truncated = false;  ///< a cell at the image's right edge or the matcher's left border
    std::vector<float> tops, lows, depths;
    std::vector<float> tops_behind;  ///< tops of lower cells far behind the segment's nearest
                                     ///< cell of their column band (behind_gap_m)
    std::vector<Eigen::Vector3d> footprint;  ///< (x, z, pixels) of each cell
};

std::vector<SegmentStats> gather_segments(Grid& g, std::vector<int>& parent, const Rig& rig,
                                          int width_px, const GeometryOptions& o) {
    // What stereo sees ends at the image's right edge and, on the left, at the column below
    // which nothing at a cell's depth has a match in the right view (offset + d); the matcher
    // leaves those borders ragged by a few columns.
    constexpr double kEdgeColumns = 8.0;
    std::vector<int> root_segment(g.cells.size(), -1);
    std::vector<SegmentStats> stats;
    for (int i = 0; i < static_cast<int>(g.cells.size()); ++i) {
        if (parent[static_cast<std::size_t>(i)] < 0) continue;
        Cell& c = g.cells[static_cast<std::size_t>(i)];
        int& s = root_segment[static_cast<std::size_t>(find_root(parent, i))];
        if (s < 0) {
            s = static_cast<int>(stats.size());
            stats.emplace_back();
        }
        c.segment = s;
        SegmentStats& st = stats[static_cast<std::size_t>(s)];
        st.pixels += static_cast<std::size_t>(c.count);
        st.tall_pixels += c.is_tall ? static_cast<std::size_t>(c.count) : 0;
        st.green += static_cast<std::size_t>(c.green);
        st.occluded += c.occluded ? static_cast<std::size_t>(c.count) : 0;
        st.lows.push_back(c.low);
        const int column_bin = i / kLayers;
        const double d = g.bin_centre[static_cast<std::size_t>(column_bin % g.bins_d)];
        const double z = rig.fb / d;
        const double u = ((column_bin / g.bins_d) + 0.5) * o.column_bin_px;
        const double u_lo = (column_bin / g.bins_d) * o.column_bin_px;
        if (u_lo <= rig.offset + d + kEdgeColumns ||
            u_lo + o.column_bin_px - 1 >= width_px - 1 - kEdgeColumns) {
            st.truncated = true;
        }
        if (u_lo <= rig.offset + d + kEdgeColumns) {
            st.border_pixels += static_cast<std::size_t>(c.count);
        }
        st.depths.push_back(static_cast<float>(z));
        st.footprint.emplace_back((u - rig.cx) * z / rig.fx, z, c.count);
    }
    // Tops last: a lower cell farther than behind_gap_m beyond the segment's nearest lower
    // cell in its column band is a surface seen above or beside the nearer thing (the back of
    // a bus a metre or two beyond a row's last car at 30 m, between the car's roof and a crown:
    // one disparity bin there spans 2 m), not the thing's own top.
    const auto band_key = [&](int i) {
        return static_cast<std::int64_t>(g.cells[static_cast<std::size_t>(i)].segment) * g.bins_u +
               (i / kLayers) / g.bins_d;
    };
    const auto cell_depth = [&](const Cell& c) { return rig.fb * c.count / c.d_sum; };
    std::unordered_map<std::int64_t, double> nearest;  // per (segment, column band), metres
    for (int i = 0; i < static_cast<int>(g.cells.size()); i += kLayers) {
        const Cell& c = g.cells[static_cast<std::size_t>(i)];
        if (c.segment < 0) continue;
        const auto [it, added] = nearest.try_emplace(band_key(i), cell_depth(c));
        if (!added) it->second = std::min(it->second, cell_depth(c));
    }
    for (int i = 0; i < static_cast<int>(g.cells.size()); ++i) {
        const Cell& c = g.cells[static_cast<std::size_t>(i)];
        if (c.segment < 0) continue;
        SegmentStats& st = stats[static_cast<std::size_t>(c.segment)];
        const bool behind = i % kLayers == 0 && o.behind_gap_m > 0.0 &&
                            cell_depth(c) > nearest.at(band_key(i)) + o.behind_gap_m;
        (behind ? st.tops_behind : st.tops).push_back(c.count > 1 ? c.top2 : c.top1);
    }
    // Cells of one kind make a linked segment; a cluster is tall when most of its pixels are.
    for (SegmentStats& st : stats) st.tall = 2 * st.tall_pixels > st.pixels;
    return stats;
}

/// The rules: a class for a segment from its height, width and green share.
Segment classify(SegmentStats& st, const Classes& cls, const GeometryOptions& o) {
    Segment seg;
    seg.pixels = st.pixels;
    // The top is the segment's own cells' (unless it is tall, or most cells lie far behind);
    // the spread below reads every cell.
    std::vector<float> all = st.tops;
    all.insert(all.end(), st.tops_behind.begin(), st.tops_behind.end());
    std::vector<float>& own = st.tall || st.tops.size() < st.tops_behind.size() ? all : st.tops;
    seg.cells = all.size();
    seg.top_m = quantile(own, 0.97);
    seg.top_q25_m = quantile(all, 0.25);
    // A wall or fence keeps one height along its length; a car's tops range from its bonnet
    // or boot (0.8-1.1 m) to its roof.
    const double top_spread = quantile(all, 0.97) - seg.top_q25_m;
    seg.low_m = quantile(st.lows, 0.1);
    std::tie(seg.width_m, seg.thickness_m) = footprint_extents(st.footprint);
    seg.depth_m = quantile(st.depths, 0.5);
    seg.near_m = quantile(st.depths, 0.05);
    seg.far_m = quantile(st.depths, 0.95);
    seg.green = st.pixels ? static_cast<double>(st.green) / st.pixels : 0.0;
    seg.occluded = st.pixels ? static_cast<double>(st.occluded) / st.pixels : 0.0;
    seg.tall = st.tall;
    const auto set = [&](std::uint16_t c, const char* label) {
        seg.class_index = c;
        seg.label = label;
    };
    const bool green = seg.green >= o.green_fraction;
    const bool narrow = seg.width_m < o.pole_max_width_m;
    if (seg.top_m < o.low_max_height_m) {
        green ? set(cls.terrain, "terrain") : set(cls.sidewalk, "sidewalk");
    } else if (green) {
        set(cls.vegetation, "vegetation");
    } else if (st.tall || seg.top_m >= o.building_min_height_m) {
        narrow ? set(cls.pole, "pole") : set(cls.building, "building");
    } else if (seg.width_m < o.car_min_width_m && !st.truncated) {
        // (Cut by the edge of what stereo sees, its width is only what shows: no test of it.)
        if (seg.top_m >= 1.0 && seg.top_m <= 2.2 && !narrow) {
            set(cls.person, "person");
        } else {
            narrow&& seg.top_m >= 2.0 ? set(cls.pole, "pole") : set(cls.other, "static");
        }
    } else if (top_spread < (seg.depth_m < o.wall_near_depth_m ? o.wall_top_spread_near_m
                                                               : o.wall_top_spread_m) &&
               seg.width_m > o.wall_min_width_m) {
        // Level along more than a car's width: a wall when thin, else kerbside clutter (bins,
        // a post box and bollards, a wall's foot behind them) seen together.
        seg.thickness_m < o.wall_max_thickness_m ? set(cls.wall, "wall") : set(cls.other, "static");
    } else if (2 * st.occluded > st.pixels) {
        set(cls.other, "static");  // its top is hidden: no telling a car from a wall's foot
    } else if (2 * st.border_pixels > st.pixels) {
        // Mostly at or beyond the matcher's left border at its own depth, where the right view
        // shows nothing at that depth: the matcher's guesses for a surface it cannot see (a
        // facade by the image's left edge, matched metres behind itself), or a sliver.
        set(cls.other, "static");
    } else if (seg.top_m >= o.car_min_height_m && seg.top_m <= o.car_max_height_m &&
               seg.low_m < o.low_max_height_m) {
        set(cls.car, "car");
    } else {
        set(cls.other, "static");
    }
    return seg;
}

/// Sky above the horizon wherever no segment holds the pixel.
void label_sky(const Grid* g, int w, double horizon_v, std::uint16_t sky, ClassImage& out) {
    if (sky == kVoidClass) return;
    const int rows = std::clamp(static_cast<int>(std::floor(horizon_v)), 0, out.height_px);
    for (std::size_t p = 0; p < static_cast<std::size_t>(rows) * w; ++p) {
        if (out.class_index[p] != kVoidClass) continue;
        const std::int32_t cell = g ? g->pixel_cell[p] : -1;
        if (cell < 0 || g->cells[static_cast<std::size_t>(cell)].segment < 0) {
            out.class_index[p] = sky;
        }
    }
}

}  // namespace

SceneGeometry derive_semantics(const DisparityMap& disparity, const StereoCamera& camera,
                               const ImageU8& left, const Palette& palette,
                               const GeometryOptions& o) {
    o.validate();
    const int w = disparity.width_px, h = disparity.height_px;
    if (!left.empty() && (left.width_px != w || left.height_px != h)) {
        throw std::invalid_argument("left image and disparity differ in size");
    }
    if (!(camera.baseline_m > 0.0) || !(camera.fx_px > 0.0) || !(camera.fy_px > 0.0)) {
        throw std::invalid_argument("camera: fx, fy and baseline must be > 0");
    }
    const Classes cls(palette);
    const Rig rig(camera);
    SceneGeometry out;
    out.classes.width_px = w;
    out.classes.height_px = h;
    out.classes.class_index.assign(static_cast<std::size_t>(w) * h, kVoidClass);
    out.ground = estimate_ground(disparity, camera, o);
    if (!out.ground.found) {
        out.warnings.push_back("no ground found: " + out.ground.problem +
                               "; only sky is labelled, no objects");
        for (std::size_t p = 0; p < out.classes.class_index.size(); ++p) {
            if (!(disparity.disparity_px[p] > 0.0f)) out.classes.class_index[p] = cls.sky;
        }
        if (cls.sky == kVoidClass)
            out.classes.class_index.assign(out.classes.class_index.size(), kVoidClass);
        return out;
    }
    Grid grid = fill_grid(disparity, rig, left, out.ground, o, cls.road, out.classes);
    std::vector<int> parent = o.segmentation == "clusters" ? cluster_cells(grid, disparity, rig, o)
                                                           : link_cells(grid, disparity, rig, o);
    std::vector<SegmentStats> stats = gather_segments(grid, parent, rig, w, o);
    std::vector<std::uint16_t> segment_class(stats.size(), kVoidClass);
    for (std::size_t s = 0; s < stats.size(); ++s) {
        out.segments.push_back(classify(stats[s], cls, o));
        segment_class[s] = out.segments.back().class_index;
    }
    out.segment_of_pixel.assign(grid.pixel_cell.size(), -1);
    for (std::size_t p = 0; p < grid.pixel_cell.size(); ++p) {
        const std::int32_t cell = grid.pixel_cell[p];
        if (cell < 0) continue;
        const int s = grid.cells[static_cast<std::size_t>(cell)].segment;
        if (s >= 0) {
            out.segment_of_pixel[p] = s;
            Segment& seg = out.segments[static_cast<std::size_t>(s)];
            const int u = static_cast<int>(p % static_cast<std::size_t>(w));
            const int v = static_cast<int>(p / static_cast<std::size_t>(w));
            if (seg.u1 < 0) {
                seg.u0 = seg.u1 = u;
                seg.v0 = seg.v1 = v;
            }
            seg.u0 = std::min(seg.u0, u);
            seg.u1 = std::max(seg.u1, u);
            seg.v0 = std::min(seg.v0, v);
            seg.v1 = std::max(seg.v1, v);
            // Green pixels of a car segment are the hedge or bush it touches.
            const std::uint16_t c = segment_class[static_cast<std::size_t>(s)];
            out.classes.class_index[p] = c == cls.car && grid.pixel_green[p] ? cls.vegetation : c;
        } else if (grid.pixel_low[p]) {
            out.classes.class_index[p] = grid.pixel_green[p] ? cls.terrain : cls.sidewalk;
        }
    }
    label_sky(&grid, w, out.ground.horizon_v_px, cls.sky, out.classes);
    // Largest first; the pixels' indices follow.
    std::vector<std::size_t> order(out.segments.size());
    std::iota(order.begin(), order.end(), std::size_t{0});
    std::stable_sort(order.begin(), order.end(), [&](std::size_t a, std::size_t b) {
        return out.segments[a].pixels > out.segments[b].pixels;
    });
    std::vector<Segment> sorted;
    sorted.reserve(order.size());
    std::vector<std::int32_t> rank(order.size());
    for (std::size_t k = 0; k < order.size(); ++k) {
        rank[order[k]] = static_cast<std::int32_t>(k);
        sorted.push_back(std::move(out.segments[order[k]]));
    }
    out.segments = std::move(sorted);
    for (std::int32_t& s : out.segment_of_pixel) {
        if (s >= 0) s = rank[static_cast<std::size_t>(s)];
    }
    return out;
}

}  // namespace cloud_analysis::geometry
