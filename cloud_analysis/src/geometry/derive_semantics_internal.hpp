#pragma once

/// Internals of derive_semantics shared by its files: the u-disparity grid of obstacle pixels,
/// filled and segmented in udisparity_grid.cpp, measured and classified in
/// derive_semantics.cpp. Private to the library.

#include <algorithm>
#include <array>
#include <cstddef>
#include <cstdint>
#include <optional>
#include <utility>
#include <vector>

#include <Eigen/Core>

#include "cloud_analysis/geometry/scene_geometry.hpp"

namespace cloud_analysis::geometry {

/// One u-disparity cell: the obstacle pixels of a column band at one disparity, in one of two
/// layers: below layer_height_m (where cars are) or above it (crowns, walls' upper floors).
struct Cell {
    int count = 0;          ///< obstacle pixels at or above low_cut_m
    float height_sum = 0;   ///< sum of their heights above the road, metres
    double d_sum = 0.0;     ///< sum of their disparities, px
    int green = 0;          ///< of them green
    float edges = 0;        ///< grey-level gradient magnitude summed over all its pixels not
    float level_edges = 0;  ///< green; of it, in horizontal edges (within 20 degrees of vertical)
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
    std::vector<float> pixel_height;       ///< per pixel in a cell (low ones too): height
                                           ///< above the road, m
};

inline int find_root(std::vector<int>& parent, int i) {
    while (parent[i] != i) {
        parent[i] = parent[parent[i]];
        i = parent[i];
    }
    return i;
}

/// Pass 1: road pixels labelled, every other pixel above the road counted in its cell; then the
/// cells' kinds (mark_kinds) and their tops.
Grid fill_grid(const DisparityMap& disparity, const Rig& rig, const ImageU8& left,
               const GroundEstimate& ground, const GeometryOptions& o, std::uint16_t road,
               ClassImage& out);

/// Pass 2b: each dense cell (dense_cells) linked to the dense cells of the same kind in the next
/// two column bands within link_depth_m; returns each dense cell's root (-1 for sparse cells).
std::vector<int> link_cells(Grid& g, const DisparityMap& disparity, const Rig& rig,
                            const GeometryOptions& o);

/// The alternative to link_cells (GeometryOptions::segmentation "clusters"): the dense cells,
/// as 3D points (x, mean height, z), grouped by Euclidean clustering with the
/// extractor's depth-grown distance, whatever their kind (docs/entities.md compares the two).
std::vector<int> cluster_cells(Grid& g, const DisparityMap& disparity, const Rig& rig,
                               const GeometryOptions& o);

/// The bands of rows a per-pixel pass over an image `rows` tall is split into on `threads`
/// threads (one each, at least one band, at most one a row); each band keeps results of its own,
/// merged in row order, so the values are one pass's.
inline std::size_t row_bands(int rows, int threads) {
    return static_cast<std::size_t>(std::clamp(threads, 1, std::max(rows, 1)));
}

/// Image columns [u_begin, u_end).
struct ColumnRange {
    int u_begin = 0, u_end = 0;
};

/// The whole column bands (column_bin_px wide, clipped to width_px) that hold every pixel of
/// the segments flagged in `fresh` (by Cell::segment): a pass over those segments' pixels reads
/// no other column. Empty when no cell is theirs.
ColumnRange fresh_columns(const Grid& g, const std::vector<char>& fresh, int column_bin_px,
                          int width_px);

/// Each car candidate's lean (Segment::lean), among the segments flagged `fresh`: per column band
/// (one stretch of surface), the slope of depth over height of its lower body's pixels within two
/// disparity noises (at least 0.5 m) of the band's median depth (a kerb or a bollard in front of
/// the body is another surface, not a lean); the segment's lean is the median over its bands, its
/// error the bands' spread (1.4826 median absolute deviations) over the square root of their
/// number.
/// Only the image columns `columns` are read (fresh_columns: where every pixel of those
/// segments lies).
void measure_leans(const Grid& grid, const DisparityMap& disparity, const Rig& rig,
                   const GeometryOptions& o, std::uint16_t car, const std::vector<char>& fresh,
                   ColumnRange columns, std::vector<Segment>& segments);

/// Each segment's colour, texture and surface roughness (Segment::chroma_r .. disparity_spread)
/// from its pixels in the left image (colour left neutral without one) and the disparity; only
/// the segments flagged in `fresh` (by index) are measured, reading the image columns `columns`
/// (fresh_columns), on `threads` threads by bands of rows (the same values as one pass).
void measure_appearance(const Grid& grid, const DisparityMap& disparity, const ImageU8& left,
                        const std::vector<char>& fresh, ColumnRange columns,
                        std::vector<Segment>& segments, int threads);

/// The weighted mean and the main axis (a unit vector: the covariance's first eigenvector) of a
/// footprint's points (x, z, weight); nullopt when the weights sum to 0.
std::optional<std::pair<Eigen::Vector2d, Eigen::Vector2d>> footprint_axis(
    const std::vector<Eigen::Vector3d>& pts);

/// Segments flagged in `split` (by Cell::segment) cut across their footprint's main axis into
/// equal pieces about GeometryOptions::vehicle_piece_m long (none when it spans under one and a
/// half of them): a row of parked vehicles that stereo sees as one surface, each vehicle then
/// judged on its own. Rewrites `parent` (the pieces' cells get a root of their own); whether
/// any segment was cut.
bool split_into_vehicle_pieces(Grid& g, std::vector<int>& parent, const Rig& rig,
                               const GeometryOptions& o, const std::vector<char>& split);

}  // namespace cloud_analysis::geometry
