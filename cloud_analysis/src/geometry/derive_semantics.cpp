// derive_semantics: the segments' measurements, the classification rules and the class image.

#include <algorithm>
#include <cmath>
#include <numeric>
#include <optional>
#include <stdexcept>
#include <tuple>
#include <unordered_map>
#include <utility>
#include <vector>

#include "cloud_analysis/geometry/scene_geometry.hpp"
#include "cloud_analysis/geometry/segment_classifier.hpp"
#include "cloud_analysis/support/select.hpp"
#include "cloud_analysis/support/task_queue.hpp"
#include "derive_semantics_internal.hpp"

namespace cloud_analysis::geometry {

std::optional<std::pair<Eigen::Vector2d, Eigen::Vector2d>> footprint_axis(
    const std::vector<Eigen::Vector3d>& pts) {
    double wsum = 0.0;
    Eigen::Vector2d mean = Eigen::Vector2d::Zero();
    for (const auto& p : pts) {
        mean += p.z() * p.head<2>();
        wsum += p.z();
    }
    if (wsum <= 0.0) return std::nullopt;
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
    return std::pair{mean, axis.normalized()};
}

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

/// Extents of a weighted footprint (x, z, weight) along its main axis and across it (2-98 %),
/// metres.
std::pair<double, double> footprint_extents(const std::vector<Eigen::Vector3d>& pts) {
    const auto frame = footprint_axis(pts);
    if (!frame) return {0.0, 0.0};
    const auto& [mean, axis] = *frame;
    const Eigen::Vector2d normal(-axis.y(), axis.x());
    std::vector<double> along, across;
    along.reserve(pts.size());
    across.reserve(pts.size());
    for (const auto& p : pts) {
        along.push_back(axis.dot(p.head<2>() - mean));
        across.push_back(normal.dot(p.head<2>() - mean));
    }
    const auto [along_lo, along_hi] = quantiles(along, 0.02, 0.98);
    const auto [across_lo, across_hi] = quantiles(across, 0.02, 0.98);
    return {along_hi - along_lo, across_hi - across_lo};
}

/// Statistics of one linked segment, gathered from its cells.
struct SegmentStats {
    std::size_t pixels = 0, green = 0, occluded = 0, tall_pixels = 0;
    /// Cell::edges and Cell::level_edges summed per column band (index u / column_bin_px), and
    /// the pixels there.
    std::vector<double> band_edges, band_level_edges, band_pixels;
    /// Per column band: whether its pixels may be a car's (mark_car_bands); empty when every
    /// band may.
    std::vector<char> band_car;
    std::size_t border_pixels = 0;  ///< in cells within kEdgeColumns of the matcher's left
                                    ///< border at their depth, or left of it
    bool tall = false;
    bool truncated = false;  ///< a cell at the image's right edge or the matcher's left border
    std::vector<double> tops, lows, depths;
    std::vector<double> tops_behind;  ///< tops of lower cells far behind the segment's nearest
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
            const auto bands = static_cast<std::size_t>(g.bins_u);
            stats.back().band_edges.assign(bands, 0.0);
            stats.back().band_level_edges.assign(bands, 0.0);
            stats.back().band_pixels.assign(bands, 0.0);
        }
        c.segment = s;
        SegmentStats& st = stats[static_cast<std::size_t>(s)];
        st.pixels += static_cast<std::size_t>(c.count);
        st.tall_pixels += c.is_tall ? static_cast<std::size_t>(c.count) : 0;
        st.green += static_cast<std::size_t>(c.green);
        const int column_bin = i / kLayers;
        const auto band = static_cast<std::size_t>(column_bin / g.bins_d);
        st.band_edges[band] += static_cast<double>(c.edges);
        st.band_level_edges[band] += static_cast<double>(c.level_edges);
        st.band_pixels[band] += c.count;
        st.occluded += c.occluded ? static_cast<std::size_t>(c.count) : 0;
        st.lows.push_back(c.low);
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
        st.depths.push_back(z);
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

/// Whether a car candidate has a car's horizontal edges: at least car_min_edge_share of
/// its gradient energy lies in them. When the whole segment falls short, the column bands
/// where a window edge_window_m wide at its depth reaches that share are marked as the car's
/// (a car merged with the bush or post box beside it; a window without texture holds no
/// evidence and passes); false when none does. True, marking none, without a left image or
/// with the test off.
bool mark_car_bands(SegmentStats& st, bool has_image, double depth_m, double fx,
                    const GeometryOptions& o) {
    if (!has_image || !(o.car_min_edge_share > 0.0)) return true;
    const std::size_t bands = st.band_edges.size();
    std::vector<double> energy(bands + 1, 0.0), horizontal(bands + 1, 0.0);
    for (std::size_t b = 0; b < bands; ++b) {
        energy[b + 1] = energy[b] + st.band_edges[b];
        horizontal[b + 1] = horizontal[b] + st.band_level_edges[b];
    }
    if (horizontal[bands] >= o.car_min_edge_share * energy[bands]) return true;
    const auto r = static_cast<std::size_t>(
        std::lround(0.5 * o.edge_window_m * fx / std::max(depth_m, 1.0) / o.column_bin_px));
    st.band_car.assign(bands, 0);
    bool any = false;
    for (std::size_t b = 0; b < bands; ++b) {
        if (!(st.band_pixels[b] > 0.0)) continue;
        const std::size_t lo = b > r ? b - r : 0, hi = std::min(bands, b + r + 1);
        const double e = energy[hi] - energy[lo];
        if (horizontal[hi] - horizontal[lo] >= o.car_min_edge_share * e) {
            st.band_car[b] = 1;
            any = true;
        }
    }
    return any;
}

/// The rules: a class for a segment from its height, width and green share.
Segment classify(SegmentStats& st, const Classes& cls, bool has_image, double fx,
                 const GeometryOptions& o) {
    Segment seg;
    seg.pixels = st.pixels;
    // The top is the segment's own cells' (unless it is tall, or most cells lie far behind);
    // the spread below reads every cell.
    std::vector<double> all = st.tops;
    all.insert(all.end(), st.tops_behind.begin(), st.tops_behind.end());
    std::vector<double>& own = st.tall || st.tops.size() < st.tops_behind.size() ? all : st.tops;
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
    if (has_image) {
        const double edges = std::accumulate(st.band_edges.begin(), st.band_edges.end(), 0.0);
        const double level =
            std::accumulate(st.band_level_edges.begin(), st.band_level_edges.end(), 0.0);
        seg.horizontal_edges = edges > 0.0 ? level / edges : 0.0;
    }
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
               seg.low_m < o.low_max_height_m &&
               mark_car_bands(st, has_image, seg.depth_m, fx, o)) {
        set(cls.car, "car");
    } else {
        set(cls.other, "static");
    }
    return seg;
}

/// Car candidates flagged `fresh` leaning beyond car_max_lean by twice their error (a bank's
/// foot) are static.
void drop_leaning_cars(const Classes& cls, const GeometryOptions& o, const std::vector<char>& fresh,
                       std::vector<Segment>& segments, std::vector<std::uint16_t>& segment_class) {
    if (!(o.car_max_lean > 0.0)) return;
    for (std::size_t s = 0; s < segments.size(); ++s) {
        if (!fresh[s]) continue;
        Segment& seg = segments[s];
        if (seg.class_index == cls.car && std::isfinite(seg.lean) &&
            seg.lean - 2.0 * seg.lean_error > o.car_max_lean) {
            seg.class_index = cls.other;
            seg.label = "static";
            segment_class[s] = cls.other;
        }
    }
}

/// What a segment classifier decides (GeometryOptions::classifier, ::person_classifier): the
/// class it gives the segments its trees call the target, that class's label, and the member of
/// Segment that keeps the trees' share.
struct Decision {
    std::uint16_t target;
    const char* label;
    double Segment::*votes;
};

/// A classifier's call on each segment flagged `fresh`, but those of class `asked_elsewhere`: one
/// more of its trees than its vote threshold call the target makes it the target's class (the
/// rules' car bands kept), a segment of that class it does not call one is static (`other`); the
/// rules' other classes stand.
void classify_segments(const SegmentClassifier& classifier, const Decision& d,
                       std::optional<std::uint16_t> asked_elsewhere, std::uint16_t other,
                       const std::vector<char>& fresh, std::vector<Segment>& segments,
                       std::vector<std::uint16_t>& segment_class) {
    for (std::size_t s = 0; s < segments.size(); ++s) {
        Segment& seg = segments[s];
        if (!fresh[s] || seg.class_index == asked_elsewhere) continue;
        seg.*d.votes = classifier.votes(seg.features);
        const bool called = seg.*d.votes > classifier.vote_threshold();
        if (called && seg.class_index != d.target) {
            seg.class_index = d.target;
            seg.label = d.label;
        } else if (!called && seg.class_index == d.target) {
            seg.class_index = other;
            seg.label = "static";
        }
        segment_class[s] = seg.class_index;
    }
}

/// A long car of the rules that the trees reject may be a row of vehicles that stereo sees as
/// one surface: such segments (spanning 1.5 vehicle_piece_m or more) are cut into pieces
/// (split_into_vehicle_pieces) and the pieces judged (`judge`, given which segments are new);
/// the other segments keep their judgement. `stats` and `segments` become the new segments'.
template <typename Judge>
void split_rejected_rows(Grid& grid, std::vector<int>& parent, const Rig& rig, int width_px,
                         const GeometryOptions& o, std::vector<SegmentStats>& stats,
                         std::vector<Segment>& segments, const Judge& judge) {
    std::vector<char> split(segments.size(), 0);
    for (std::size_t s = 0; s < segments.size(); ++s) {
        split[s] = segments[s].rules_label == "car" && segments[s].label != "car" &&
                   segments[s].width_m >= 1.5 * o.vehicle_piece_m;
    }
    if (std::none_of(split.begin(), split.end(), [](char c) { return c != 0; })) return;
    std::vector<int> before_of_cell(grid.cells.size());
    for (std::size_t i = 0; i < grid.cells.size(); ++i) before_of_cell[i] = grid.cells[i].segment;
    if (!split_into_vehicle_pieces(grid, parent, rig, o, split)) return;
    std::vector<Segment> before = std::move(segments);
    std::vector<SegmentStats> before_stats = std::move(stats);
    stats = gather_segments(grid, parent, rig, width_px, o);
    std::vector<int> kept(stats.size(), -1);  // per new segment: the old one it is, if unsplit
    for (std::size_t i = 0; i < grid.cells.size(); ++i) {
        const int now = grid.cells[i].segment, was = before_of_cell[i];
        if (now >= 0 && was >= 0 && !split[static_cast<std::size_t>(was)]) {
            kept[static_cast<std::size_t>(now)] = was;
        }
    }
    segments.assign(stats.size(), Segment{});
    std::vector<char> fresh(stats.size(), 1);
    for (std::size_t s = 0; s < stats.size(); ++s) {
        if (kept[s] < 0) continue;
        segments[s] = std::move(before[static_cast<std::size_t>(kept[s])]);
        // The rules' car bands (mark_car_bands) as they were judged.
        stats[s].band_car = std::move(before_stats[static_cast<std::size_t>(kept[s])].band_car);
        fresh[s] = 0;
    }
    judge(fresh);
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

/// Without a road: sky wherever the disparity is missing (nothing when the palette has no
/// sky), every other pixel void.
void label_without_ground(const DisparityMap& disparity, std::uint16_t sky, ClassImage& classes) {
    for (std::size_t p = 0; p < classes.class_index.size(); ++p) {
        if (!(disparity.disparity_px[p] > 0.0f)) classes.class_index[p] = sky;
    }
    if (sky == kVoidClass) classes.class_index.assign(classes.class_index.size(), kVoidClass);
}

/// An image box being grown, inclusive; empty while u1 < 0.
struct PixelBox {
    int u0 = 0, v0 = 0, u1 = -1, v1 = -1;
    void add(int u, int v) {
        if (u1 < 0) {
            u0 = u1 = u;
            v0 = v1 = v;
        }
        u0 = std::min(u0, u), u1 = std::max(u1, u);
        v0 = std::min(v0, v), v1 = std::max(v1, v);
    }
};

/// What labelling the segments' pixels reads.
struct SegmentLabels {
    const Grid& grid;
    const Classes& cls;
    const std::vector<std::uint16_t>& segment_class;
    const std::vector<SegmentStats>& stats;
    const std::vector<std::int32_t>& rank;  ///< each segment's index once sorted
    int column_bin_px;
};

/// label_segment_pixels over rows [v_begin, v_end): each segment's box grown in `boxes`.
void label_rows(const SegmentLabels& in, int w, std::size_t v_begin, std::size_t v_end,
                std::vector<PixelBox>& boxes, SceneGeometry& out) {
    const Grid& grid = in.grid;
    for (auto v = v_begin; v < v_end; ++v) {
        for (int u = 0; u < w; ++u) {
            const std::size_t p = v * static_cast<std::size_t>(w) + static_cast<std::size_t>(u);
            const std::int32_t cell = grid.pixel_cell[p];
            if (cell < 0) continue;
            const int s = grid.cells[static_cast<std::size_t>(cell)].segment;
            if (s < 0) {
                if (grid.pixel_low[p]) {
                    out.classes.class_index[p] =
                        grid.pixel_green[p] ? in.cls.terrain : in.cls.sidewalk;
                }
                continue;
            }
            out.segment_of_pixel[p] = in.rank[static_cast<std::size_t>(s)];
            boxes[static_cast<std::size_t>(s)].add(u, static_cast<int>(v));
            // A car segment's bands without a car's horizontal edges are clutter beside it; its
            // green pixels are the hedge or bush it touches.
            std::uint16_t c = in.segment_class[static_cast<std::size_t>(s)];
            const std::vector<char>& bands = in.stats[static_cast<std::size_t>(s)].band_car;
            if (c == in.cls.car && grid.pixel_green[p]) {
                c = in.cls.vegetation;
            } else if (c == in.cls.car && !bands.empty() &&
                       !bands[static_cast<std::size_t>(u / in.column_bin_px)]) {
                c = in.cls.other;
            }
            out.classes.class_index[p] = c;
        }
    }
}

/// Each pixel of a segment: its segment's index once sorted (SegmentLabels::rank), class
/// (segment_class) and image box; a pixel below low_cut_m in no segment: sidewalk or terrain. By
/// bands of rows (row_bands) on `threads` threads: each pixel is written once, the boxes merged.
void label_segment_pixels(const SegmentLabels& in, int w, int threads, SceneGeometry& out) {
    out.segment_of_pixel.assign(in.grid.pixel_cell.size(), -1);
    const auto rows = static_cast<int>(in.grid.pixel_cell.size() / static_cast<std::size_t>(w));
    const std::size_t parts = row_bands(rows, threads);
    std::vector<std::vector<PixelBox>> boxes(parts, std::vector<PixelBox>(out.segments.size()));
    for_each_chunk(static_cast<std::size_t>(rows), parts,
                   [&](std::size_t k, std::size_t first, std::size_t last) {
                       label_rows(in, w, first, last, boxes[k], out);
                   });
    for (std::size_t s = 0; s < out.segments.size(); ++s) {
        Segment& seg = out.segments[s];
        PixelBox box{seg.u0, seg.v0, seg.u1, seg.v1};
        for (const auto& part : boxes) {
            if (part[s].u1 < 0) continue;
            box.add(part[s].u0, part[s].v0);
            box.add(part[s].u1, part[s].v1);
        }
        seg.u0 = box.u0, seg.v0 = box.v0, seg.u1 = box.u1, seg.v1 = box.v1;
    }
}

/// Each segment's place once sorted by pixels, largest first (ties in their order).
std::vector<std::int32_t> largest_first(const std::vector<Segment>& segments) {
    std::vector<std::size_t> order(segments.size());
    std::iota(order.begin(), order.end(), std::size_t{0});
    std::stable_sort(order.begin(), order.end(), [&](std::size_t a, std::size_t b) {
        return segments[a].pixels > segments[b].pixels;
    });
    std::vector<std::int32_t> rank(order.size());
    for (std::size_t k = 0; k < order.size(); ++k) rank[order[k]] = static_cast<std::int32_t>(k);
    return rank;
}

/// The segments put at their places in `rank` (largest_first), as the pixels name them.
void sort_segments(const std::vector<std::int32_t>& rank, SceneGeometry& out) {
    std::vector<Segment> sorted(out.segments.size());
    for (std::size_t s = 0; s < rank.size(); ++s) {
        sorted[static_cast<std::size_t>(rank[s])] = std::move(out.segments[s]);
    }
    out.segments = std::move(sorted);
}

}  // namespace

ColumnRange fresh_columns(const Grid& g, const std::vector<char>& fresh, int column_bin_px,
                          int width_px) {
    const int per_band = g.bins_d * kLayers;
    int first = g.bins_u, last = -1;
    for (std::size_t i = 0; i < g.cells.size(); ++i) {
        const int s = g.cells[i].segment;
        if (s < 0 || !fresh[static_cast<std::size_t>(s)]) continue;
        const int band = static_cast<int>(i) / per_band;
        first = std::min(first, band);
        last = std::max(last, band);
    }
    if (last < 0) return {};
    return {first * column_bin_px, std::min(width_px, (last + 1) * column_bin_px)};
}

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
        label_without_ground(disparity, cls.sky, out.classes);
        return out;
    }
    Grid grid = fill_grid(disparity, rig, left, out.ground, o, cls.road, out.classes);
    std::vector<int> parent = o.segmentation == "clusters" ? cluster_cells(grid, disparity, rig, o)
                                                           : link_cells(grid, disparity, rig, o);
    std::vector<SegmentStats> stats = gather_segments(grid, parent, rig, w, o);
    std::vector<std::uint16_t> segment_class;
    const bool has_image = !left.empty() && left.width_px == w && left.height_px == h;
    // The rules, then the classifier, on the segments flagged `fresh`; the others are as judged.
    const auto judge = [&](const std::vector<char>& fresh) {
        segment_class.resize(stats.size(), kVoidClass);
        out.segments.resize(stats.size());
        for (std::size_t s = 0; s < stats.size(); ++s) {
            if (fresh[s]) out.segments[s] = classify(stats[s], cls, has_image, rig.fx, o);
            segment_class[s] = out.segments[s].class_index;
        }
        const ColumnRange columns = fresh_columns(grid, fresh, o.column_bin_px, w);
        measure_leans(grid, disparity, rig, o, cls.car, fresh, columns, out.segments);
        drop_leaning_cars(cls, o, fresh, out.segments, segment_class);
        measure_appearance(grid, disparity, left, fresh, columns, out.segments, o.threads);
        for (std::size_t s = 0; s < stats.size(); ++s) {
            if (!fresh[s]) continue;
            out.segments[s].rules_label = out.segments[s].label;
            out.segments[s].features = segment_features(out.segments[s], rig.fx, rig.fy);
        }
        // Vehicles first; people among the segments that are no vehicle.
        if (o.classifier) {
            classify_segments(*o.classifier, {cls.car, "car", &Segment::vehicle_votes},
                              std::nullopt, cls.other, fresh, out.segments, segment_class);
        }
        if (o.person_classifier && cls.person != kVoidClass) {
            classify_segments(*o.person_classifier, {cls.person, "person", &Segment::person_votes},
                              cls.car, cls.other, fresh, out.segments, segment_class);
        }
    };
    judge(std::vector<char>(stats.size(), 1));
    if (o.classifier) split_rejected_rows(grid, parent, rig, w, o, stats, out.segments, judge);

    // Largest segment first; the pixels name them by their places in that order.
    const std::vector<std::int32_t> rank = largest_first(out.segments);
    label_segment_pixels({grid, cls, segment_class, stats, rank, o.column_bin_px}, w, o.threads,
                         out);
    label_sky(&grid, w, out.ground.horizon_v_px, cls.sky, out.classes);
    sort_segments(rank, out);
    return out;
}

}  // namespace cloud_analysis::geometry
