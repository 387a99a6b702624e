// u-disparity grid of derive_semantics: pixels counted in cells, cells linked into segments.

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <utility>
#include <vector>

#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>

#include "cloud_analysis/entities/cluster.hpp"
#include "cloud_analysis/io/mat_view.hpp"
#include "cloud_analysis/support/task_queue.hpp"
#include "derive_semantics_internal.hpp"

namespace cloud_analysis::geometry {
namespace {

/// Heights within this of a tall cell's are its surface's (GeometryOptions::split_surface_px):
/// one image row spans 0.04 m at 30 m, metres.
constexpr float kSplitSurfaceMarginM = 0.05f;

/// Whether heights lo to hi lie within tall cell t's (kSplitSurfaceMarginM).
bool within_heights(const Cell& t, float lo, float hi) {
    return lo >= t.low - kSplitSurfaceMarginM && hi <= t.high + kSplitSurfaceMarginM;
}

void unite(std::vector<int>& parent, int a, int b) {
    a = find_root(parent, a);
    b = find_root(parent, b);
    if (a != b) parent[std::max(a, b)] = std::min(a, b);
}

bool is_green(int r, int g, int b) { return g >= r + 6 && g * 10 >= r * 11 && g * 10 >= b * 11; }

/// Row v's sums of each pixel's colour over the columns of its window (at most 129 * 255 per
/// channel), 3 channels a pixel.
void sums_across(const ImageU8& left, int v, int radius, std::int32_t* out) {
    const int w = left.width_px;
    const std::uint8_t* p = left.at(0, v);
    std::array<std::int32_t, 3> sum{0, 0, 0};
    for (int u = 0; u < std::min(w, radius); ++u) {
        for (int c = 0; c < 3; ++c) sum[c] += p[u * 3 + c];
    }
    for (int u = 0; u < w; ++u) {
        for (int c = 0; c < 3; ++c) {
            if (u + radius < w) sum[c] += p[(u + radius) * 3 + c];
            if (u - radius - 1 >= 0) sum[c] -= p[(u - radius - 1) * 3 + c];
            out[u * 3 + c] = sum[c];
        }
    }
}

/// green_mask over rows [v0, v1): the window sums slid down the rows, each row's sums across
/// computed once and kept only while in the window (a ring of 2 radius + 1 rows). The mean
/// colour is floored without a division per pixel: (s + 0.5) / n lies at least 0.5 / n from an
/// integer, far beyond the rounding of (s + 0.5) times the window's reciprocal (a few ulp of at
/// most 255.5), so truncating that product floors s / n exactly.
void green_rows(const ImageU8& left, int radius, const std::vector<double>& per_column, int v0,
                int v1, char* mask) {
    const int w = left.width_px, h = left.height_px, span = 2 * radius + 1;
    const std::size_t row_len = static_cast<std::size_t>(w) * 3;
    std::vector<std::int32_t> ring(row_len * static_cast<std::size_t>(span));
    const auto slot = [&](int v) {
        return ring.data() + static_cast<std::size_t>(v % span) * row_len;
    };
    std::vector<std::int32_t> down(row_len, 0);
    const auto add = [&](int v, int sign) {
        const std::int32_t* r = slot(v);
        for (std::size_t k = 0; k < row_len; ++k) down[k] += sign * r[k];
    };
    // The window's rows above v0, less the one that enters at v0.
    for (int v = std::max(0, v0 - radius); v < std::min(h, v0 + radius); ++v) {
        sums_across(left, v, radius, slot(v));
        add(v, 1);
    }
    for (int v = v0; v < v1; ++v) {
        // The row leaving shares its slot with the one entering: out first.
        if (v - radius - 1 >= std::max(0, v0 - radius)) add(v - radius - 1, -1);
        if (v + radius < h) {
            sums_across(left, v + radius, radius, slot(v + radius));
            add(v + radius, 1);
        }
        const double per_row = 1.0 / (std::min(h, v + radius + 1) - std::max(0, v - radius));
        char* m = mask + static_cast<std::size_t>(v) * w;
        const std::int32_t* s = down.data();
        for (int u = 0; u < w; ++u, s += 3) {
            const double inverse = per_row * per_column[static_cast<std::size_t>(u)];
            const auto mean = [&](int c) { return static_cast<int>((s[c] + 0.5) * inverse); };
            m[u] = is_green(mean(0), mean(1), mean(2));
        }
    }
}

/// Per pixel: whether the mean colour of its (2 radius + 1)^2 window is green (foliage's own
/// shadows between sunlit leaves are green only on average); all 0 without a colour image. At
/// the image's border the window holds only the pixels inside. Rows in `threads` stripes.
std::vector<char> green_mask(const ImageU8& left, int w, int h, int radius, int threads) {
    std::vector<char> mask(static_cast<std::size_t>(w) * h, 0);
    if (left.channels != 3 || left.empty() || left.width_px != w || left.height_px != h) {
        return mask;
    }
    std::vector<double> per_column(static_cast<std::size_t>(w));
    for (int u = 0; u < w; ++u) {
        per_column[static_cast<std::size_t>(u)] =
            1.0 / (std::min(w, u + radius + 1) - std::max(0, u - radius));
    }
    for_each_chunk(static_cast<std::size_t>(h), static_cast<std::size_t>(std::max(1, threads)),
                   [&](std::size_t, std::size_t v0, std::size_t v1) {
                       green_rows(left, radius, per_column, static_cast<int>(v0),
                                  static_cast<int>(v1), mask.data());
                   });
    return mask;
}

/// The left image in grey (grey_of), averaged over step x step boxes: the grid the edges are
/// read on. Empty without an image of the disparity's size.
struct EdgeGrid {
    cv::Mat grey;  ///< CV_8UC1, continuous
    int step = 1;
};

EdgeGrid edge_grid(const ImageU8& left, int w, int h, int step) {
    EdgeGrid e;
    if (left.empty() || left.width_px != w || left.height_px != h) return e;
    e.step = std::max(1, step);
    const cv::Mat grey = grey_of(left);
    if (e.step == 1) {
        e.grey = grey.isContinuous() ? grey : grey.clone();
    } else {
        cv::resize(grey, e.grey, cv::Size(w / e.step, h / e.step), 0.0, 0.0, cv::INTER_AREA);
    }
    return e;
}

/// Adds the 3x3 Sobel gradient of the edge grid at pixel (u, v) (not on the grid's border) to a
/// cell's edges, and to its level edges when the gradient points within 20 degrees of vertical.
void add_edge(const EdgeGrid& e, int u, int v, Cell& c) {
    constexpr float kTan20 = 0.36397f;
    const int x = u / e.step, y = v / e.step;
    if (x < 1 || y < 1 || x + 1 >= e.grey.cols || y + 1 >= e.grey.rows) return;
    const int w = e.grey.cols;
    const std::uint8_t* p = e.grey.ptr<std::uint8_t>(y) + x;
    const int gx = (p[-w + 1] + 2 * p[1] + p[w + 1]) - (p[-w - 1] + 2 * p[-1] + p[w - 1]);
    const int gy = (p[w - 1] + 2 * p[w] + p[w + 1]) - (p[-w - 1] + 2 * p[-w] + p[-w + 1]);
    const auto fx = static_cast<float>(gx), fy = static_cast<float>(gy);
    const float magnitude = std::sqrt(fx * fx + fy * fy);
    c.edges += magnitude;
    if (std::abs(fx) <= kTan20 * std::abs(fy)) c.level_edges += magnitude;
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

/// An empty grid over the disparity map: its column bands, disparity bins and cells, and the
/// per-pixel arrays.
Grid make_grid(const DisparityMap& disparity, const Rig& rig, const GeometryOptions& o) {
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
    return g;
}

/// Columns [u_begin, u_end) of the image: the cells of their column bands are theirs alone.
struct Columns {
    int u_begin = 0, u_end = 0;
};

/// The image's columns in `parts` runs of whole column bands, for threads that each fill the
/// cells of their own bands (each cell's pixels still taken in row order).
std::vector<Columns> column_parts(int w, int column_bin_px, int parts) {
    const int bands = (w + column_bin_px - 1) / column_bin_px;
    parts = std::clamp(parts, 1, std::max(1, bands));
    std::vector<Columns> out;
    for (int k = 0; k < parts; ++k) {
        out.push_back({std::min(w, bands * k / parts * column_bin_px),
                       std::min(w, bands * (k + 1) / parts * column_bin_px)});
    }
    return out;
}

/// What the pixel passes read of the left image: green pixels and the grid of their edges.
struct ImageCues {
    std::vector<char> green;
    EdgeGrid edges;
};

/// Road pixels labelled, every other pixel above the road counted in its cell, in `columns`;
/// returns the lower-layer pixels near the layers' border, counted once their cells' mean
/// disparity is known (count_lower_at_cut).
std::vector<std::size_t> count_pixels(const DisparityMap& disparity, const Rig& rig,
                                      const ImageCues& cues, const GroundEstimate& ground,
                                      const GeometryOptions& o, std::uint16_t road, Columns columns,
                                      Grid& g, ClassImage& out) {
    const int w = disparity.width_px, h = disparity.height_px;
    const Eigen::Vector3d n = ground.plane.normal;
    const double plane_d = ground.plane.d;
    const double min_d = rig.fb / o.max_depth_m;
    // Height error of a road point at depth z for a disparity error e: h_cam * z * e / (f B).
    const double slope = o.disparity_noise_px * plane_d / rig.fb;
    const auto tall_m = static_cast<float>(o.layer_height_m);
    const auto band_m = static_cast<float>(o.continuity_band_m);
    const std::vector<char>& green_px = cues.green;
    const EdgeGrid& edges = cues.edges;
    std::vector<std::size_t> lower_at_cut;  // lower-layer pixels near the layers' border
    for (int v = 0; v < h; ++v) {
        const std::size_t row = static_cast<std::size_t>(v) * w;
        const double row_term = n.y() * (v - rig.cy) / rig.fy + n.z();
        for (int u = columns.u_begin; u < columns.u_end; ++u) {
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
            g.pixel_height[row + u] = hf;
            const bool green = green_px[row + u] != 0;
            g.pixel_green[row + u] = green ? 1 : 0;
            if (!green && !edges.grey.empty()) {
                add_edge(edges, u, v, g.cells[static_cast<std::size_t>(cell)]);
            }
            if (height < o.low_cut_m) {
                g.pixel_low[row + u] = 1;
                continue;
            }
            Cell& c = g.cells[static_cast<std::size_t>(cell)];
            ++c.count;
            c.d_sum += d;
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
    return lower_at_cut;
}

/// A lower cell's border rows continue its own surface only at its depth: at range one bin
/// spans metres, and the surface seen over a thing's top (a bus's back 1 m beyond a car's
/// roof at 30 m) shares its cell, pixel-locked a few tenths of a pixel farther. A surface
/// along the ray spreads over the whole bin, so only pixels farther than both limits drop.
void count_lower_at_cut(const std::vector<std::size_t>& lower_at_cut, const DisparityMap& disparity,
                        const Rig& rig, const GeometryOptions& o,
                        const std::vector<double>& cell_mean_d, Grid& g) {
    for (const std::size_t p : lower_at_cut) {
        const auto cell = static_cast<std::size_t>(g.pixel_cell[p]);
        Cell& c = g.cells[cell];
        const double d = double{disparity.disparity_px[p]} - rig.offset;
        const double mean_d = cell_mean_d[cell];
        if (d >= mean_d - o.continuity_behind_px ||
            rig.fb / d <= rig.fb / mean_d + o.continuity_behind_m) {
            ++c.at_cut;
        }
    }
}

/// Whether lower-layer pixel height hf of cell c lies within a tall cell whose surface c
/// holds in part: that surface's pixels, not c's own.
bool on_split_surface(const Grid& g, const Cell& c, float hf) {
    return std::any_of(c.surface.begin(), c.surface.end(), [&](int j) {
        return j >= 0 && within_heights(g.cells[static_cast<std::size_t>(j)], hf, hf);
    });
}

/// Height hf into a cell's highest and second highest.
void raise_top(float hf, float& top, float& second) {
    if (hf > top) {
        second = top;
        top = hf;
    } else if (hf > second) {
        second = hf;
    }
}

/// The cells' tops, after their kinds (mark_kinds), from the pixels at the cell's depth: at range
/// one disparity bin spans metres, and the surface just behind a thing (a bus's side above a car's
/// roof, 1-2 px of disparity farther) shares its bins but not its top, nor does the lowest edge of
/// a tree's crown a metre in front of a car's end, which runs on up into the upper layer. Pixels on
/// a blend (on_blend) or at the foot of a surface above, ahead of the cell's mean, count
/// only in cells that have no other.
void find_tops(const DisparityMap& disparity, const Rig& rig, const GeometryOptions& o,
               const std::vector<double>& cell_mean_d, Columns columns, Grid& g) {
    const int w = disparity.width_px, h = disparity.height_px;
    for (int v = 0; v < h; ++v) {
        const std::size_t row = static_cast<std::size_t>(v) * w;
        for (int u = columns.u_begin; u < columns.u_end; ++u) {
            const std::int32_t cell = g.pixel_cell[row + u];
            if (cell < 0 || g.pixel_low[row + u]) continue;
            Cell& c = g.cells[static_cast<std::size_t>(cell)];
            const double d = double{disparity.disparity_px[row + u]} - rig.offset;
            const double mean_d = cell_mean_d[static_cast<std::size_t>(cell)];
            if (d < mean_d - o.top_behind_px) continue;
            const float hf = g.pixel_height[row + u];
            if (hf > c.top2 || hf > c.blend2) {  // else neither pair changes
                if ((!c.is_tall && on_split_surface(g, c, hf)) ||
                    on_blend(disparity, u, v, o.blend_rows, o.blend_step_px) ||
                    (d > mean_d + o.foot_ahead_px &&
                     foot_of_surface_above(disparity, g.pixel_cell, rig.offset, u, v, d,
                                           o.blend_rows, o.blend_step_px))) {
                    raise_top(hf, c.blend1, c.blend2);
                } else {
                    raise_top(hf, c.top1, c.top2);
                }
            }
            if (v < c.top_v) {
                c.top_v = v;
                c.top_u = u;
            }
        }
    }
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

}  // namespace

Grid fill_grid(const DisparityMap& disparity, const Rig& rig, const ImageU8& left,
               const GroundEstimate& ground, const GeometryOptions& o, std::uint16_t road,
               ClassImage& out) {
    const int w = disparity.width_px, h = disparity.height_px;
    Grid g = make_grid(disparity, rig, o);
    const ImageCues cues{green_mask(left, w, h, o.green_window_px, o.threads),
                         edge_grid(left, w, h, o.edge_step_px)};
    // Each thread fills the cells of its own column bands, their pixels in row order as one
    // thread would: the sums come out the same.
    const std::vector<Columns> parts = column_parts(w, o.column_bin_px, o.threads);
    std::vector<std::vector<std::size_t>> lower_at_cut(parts.size());
    for_each_chunk(parts.size(), parts.size(), [&](std::size_t k, std::size_t, std::size_t) {
        lower_at_cut[k] = count_pixels(disparity, rig, cues, ground, o, road, parts[k], g, out);
    });
    // Each cell's mean disparity, once its pixels are counted (the passes below read it).
    std::vector<double> cell_mean_d(g.cells.size(), 0.0);
    for (std::size_t k = 0; k < g.cells.size(); ++k) {
        if (g.cells[k].count > 0) cell_mean_d[k] = g.cells[k].d_sum / g.cells[k].count;
    }
    for (const auto& part : lower_at_cut) {
        count_lower_at_cut(part, disparity, rig, o, cell_mean_d, g);
    }
    mark_kinds(g, rig, o);
    for_each_chunk(parts.size(), parts.size(), [&](std::size_t k, std::size_t, std::size_t) {
        find_tops(disparity, rig, o, cell_mean_d, parts[k], g);
    });
    for (Cell& c : g.cells) {
        if (c.top1 < -1e8f) {
            c.top1 = c.blend1;
            c.top2 = c.blend2;
        }
    }
    return g;
}

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

}  // namespace cloud_analysis::geometry
