#include "cloud_analysis/entities/row_split.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>

#include "cloud_analysis/support/select.hpp"
#include "row_split_internal.hpp"
#include "stereoscene/support/angles.hpp"

using stereoscene::support::wrap_angle;

namespace cloud_analysis::instances {

Projection project(const std::vector<Eigen::Vector3f>& pts, const Indices& idx, double dir_x,
                   double dir_z) {
    Projection p;
    p.along.resize(idx.size());
    for (std::size_t k = 0; k < idx.size(); ++k) {
        p.along[k] = double{pts[idx[k]].x()} * dir_x + double{pts[idx[k]].z()} * dir_z;
        p.lo = std::min(p.lo, p.along[k]);
        p.hi = std::max(p.hi, p.along[k]);
    }
    return p;
}

namespace {

/// Boxes wider than this many prior widths are looked at for two things side by side.
constexpr double kSideBySideWidth = 1.3;
/// The narrowest gap (0.1 m bins) that parts two things side by side.
constexpr int kSideBySideGapBins = 2;
/// How far two things side by side overlap along the gap between them, at least, metres.
constexpr double kSideBySideOverlap = 0.5;
/// How far two things in line (one behind the other) overlap across the gap between them, at
/// least, metres: no more than a rounding error apart.
constexpr double kInLineOverlap = -0.1;
/// The share of a row's points, at its near end, that a walk of cuts starts after.
constexpr double kWalkStartQuantile = 0.01;
/// The narrowest clear gap (0.1 m bins) that a walk of cuts takes one prior pitch on.
constexpr int kClearGapBins = 2;
/// The longest run of occupied 0.1 m bins inside a gap that a walk of cuts crosses (stray points
/// smeared into the gap off the thing before it).
constexpr int kGapIslandBins = 3;
using stereoscene::support::kHalfPi;

/// A longer pitch for the tall things of a row walked from its near end (vans among cars).
struct TallPitch {
    GroundPlane ground;         ///< heights are above it
    double min_height_m = 0.0;  ///< a thing whose top (98 % height) reaches this is tall
    double pitch_m = 0.0;       ///< a tall thing's pitch (its length and the row's gap)
};

/// The bins of split_along's density histogram, metres.
constexpr double kSplitBin = 0.1;

/// The density histogram of points along a direction, kSplitBin bins from lo: a bin with at
/// most kGapFraction of the median occupied bin's points is a clear gap.
struct Density {
    double lo = 0.0;
    int bins = 1;
    std::vector<int> hist;
    double gap_count = 0.0;

    bool inside(int b) const { return b >= 0 && b < bins; }
    bool is_gap(int b) const { return hist[static_cast<std::size_t>(b)] <= gap_count; }
    /// The emptiest bin within r bins of centre.
    int emptiest(int centre, int r) const {
        int best = std::clamp(centre, 0, bins - 1);
        for (int b = std::max(0, centre - r); b <= std::min(bins - 1, centre + r); ++b) {
            if (hist[static_cast<std::size_t>(b)] < hist[static_cast<std::size_t>(best)]) best = b;
        }
        return best;
    }
};

Density density_along(const Projection& p) {
    Density d;
    d.lo = p.lo;
    // Density histogram along the direction, 0.1 m bins.
    d.bins = std::max(1, static_cast<int>(std::ceil((p.hi - p.lo) / kSplitBin)) + 1);
    d.hist.assign(static_cast<std::size_t>(d.bins), 0);
    for (double a : p.along) ++d.hist[static_cast<std::size_t>((a - d.lo) / kSplitBin)];
    std::vector<int> occupied;
    for (int h : d.hist) {
        if (h > 0) occupied.push_back(h);
    }
    std::nth_element(occupied.begin(), occupied.begin() + occupied.size() / 2, occupied.end());
    d.gap_count = kGapFraction * occupied[occupied.size() / 2];
    return d;
}

/// A walk of cuts from the near end of a row over its density histogram (split_along).
struct NearEndWalk {
    const Density& density;
    const TallPitch* tall;
    int step, reach;            ///< one prior pitch on, in bins, and the reach around it
    int tall_step, tall_reach;  ///< the same for a tall thing's pitch
    /// Heights above the ground per bin, read only by a walk with a tall pitch.
    std::vector<std::vector<double>> heights;
    /// Gaps with single-bin islands of stray points merged: per gap bin, the first and last
    /// bin of its gap (-1 off gaps); read only by a walk with a tall pitch.
    std::vector<int> gap_first, gap_last;

    /// A cut in a gap wider than the cut: the next thing starts where the gap ends. A few
    /// stray points in the gap (smear off the thing before it) do not end it: a run of at
    /// most kGapIslandBins bins with a clear gap beyond it is crossed.
    int gap_end(int b, int dir) const {
        for (;;) {
            while (density.inside(b + dir) && density.is_gap(b + dir)) b += dir;
            int e = b + dir;
            for (int n = 0; n < kGapIslandBins && density.inside(e) && !density.is_gap(e); ++n) {
                e += dir;
            }
            int run = 0;
            for (int f = e; run < kClearGapBins && density.inside(f) && density.is_gap(f);
                 f += dir) {
                ++run;
            }
            if (e == b + dir || run < kClearGapBins) return b;
            b = e;
        }
    }

    /// Fills gap_first and gap_last from the density's gaps.
    void merge_gaps() {
        const int bins = density.bins;
        gap_first.assign(density.hist.size(), -1);
        gap_last = gap_first;
        for (int b = 0; b < bins;) {
            if (!density.is_gap(b)) {
                ++b;
                continue;
            }
            int e = b;
            while (density.inside(e + 1) &&
                   (density.is_gap(e + 1) || (density.inside(e + 2) && density.is_gap(e + 2)))) {
                e += density.is_gap(e + 1) ? 1 : 2;
            }
            for (int k = b; k <= e; ++k) {
                gap_first[static_cast<std::size_t>(k)] = b;
                gap_last[static_cast<std::size_t>(k)] = e;
            }
            b = e + 1;
        }
    }

    /// Bins of the widest merged gap within [first, last] (each gap counted within it), 0
    /// when none holds kClearGapBins.
    int widest_gap(int first, int last) const {
        first = std::max(first, 0);
        last = std::min(last, density.bins - 1);
        int widest = 0;
        for (int b = first; b <= last; ++b) {
            const auto k = static_cast<std::size_t>(b);
            if (gap_first[k] < 0 || (b > first && gap_first[k] == gap_first[k - 1])) continue;
            const int width = std::min(gap_last[k], last) - std::max(gap_first[k], first) + 1;
            if (width >= kClearGapBins) widest = std::max(widest, width);
        }
        return widest;
    }

    /// The next cut from the bin `from` in the direction dir: about one pitch on. When the
    /// points within that pitch are tall and no clear gap (kClearGapBins gap bins in a row)
    /// lies within reach of one prior pitch on, or a wider one lies within reach of a tall
    /// thing's pitch, one tall thing's pitch on instead.
    int next_cut(int from, int dir) const {
        const int bins = density.bins;
        const int centre = from + dir * step;
        if (!tall || tall_step <= step) return density.emptiest(centre, reach);
        bool clear = false;
        for (int b = std::max(0, centre - reach), run = 0;
             b <= std::min(bins - 1, centre + reach) && !clear; ++b) {
            run = density.is_gap(b) ? run + 1 : 0;
            clear = run >= kClearGapBins;
        }
        std::vector<double> h;
        for (int b = std::max(0, std::min(from, from + dir * step));
             b <= std::min(bins - 1, std::max(from, from + dir * step)); ++b) {
            const auto& in_bin = heights[static_cast<std::size_t>(b)];
            h.insert(h.end(), in_bin.begin(), in_bin.end());
        }
        if (h.empty() || quantile(h, 0.98) < tall->min_height_m) {
            return density.emptiest(centre, reach);
        }
        const int tall_centre = from + dir * tall_step;
        // A tall thing with a clear gap one car's pitch on: a car's end there unless a wider
        // gap lies about a van's pitch on (the dip under a van's lower rear, a metre short
        // of the gap behind it).
        if (clear && widest_gap(tall_centre - tall_reach, tall_centre + tall_reach) <=
                         widest_gap(centre - reach, centre + reach)) {
            return density.emptiest(centre, reach);
        }
        return density.emptiest(tall_centre, tall_reach);
    }
};

/// The bins of the cuts walked from the near end of the points idx (their projection p and its
/// density histogram), one prior pitch (step bins, each cut within reach of it) or, with
/// `tall`, a tall thing's pitch apart.
std::vector<int> walk_from_near_end(const std::vector<Eigen::Vector3f>& pts, const Indices& idx,
                                    const Projection& p, const Density& density, int step,
                                    int reach, const TallPitch* tall) {
    NearEndWalk walk{density, tall, step, reach, step, reach, {}, {}, {}};
    if (tall) {
        walk.tall_step = static_cast<int>(std::lround(tall->pitch_m / kSplitBin));
        walk.tall_reach = static_cast<int>(0.25 * tall->pitch_m / kSplitBin);
        walk.heights.resize(density.hist.size());
        for (std::size_t k = 0; k < p.along.size(); ++k) {
            walk.heights[static_cast<std::size_t>((p.along[k] - p.lo) / kSplitBin)].push_back(
                tall->ground.height(pts[idx[k]].cast<double>()));
        }
        walk.merge_gaps();
    }
    // The walk starts where the bulk of the points starts, not at a stray point smeared
    // towards the camera: a cut one car length from such a point falls inside the first car.
    std::vector<double> sorted = p.along;
    const auto [q_lo, q_hi] = quantiles(sorted, kWalkStartQuantile, 1.0 - kWalkStartQuantile);
    std::vector<int> cuts;
    if (std::abs(p.hi) < std::abs(p.lo)) {
        const int start = static_cast<int>((q_hi - p.lo) / kSplitBin);
        for (int b = walk.next_cut(start, -1); b >= step / 4;
             b = walk.next_cut(walk.gap_end(b, -1), -1)) {
            cuts.push_back(b);
        }
    } else {
        const int start = static_cast<int>((q_lo - p.lo) / kSplitBin);
        for (int b = walk.next_cut(start, 1); b < density.bins - step / 4;
             b = walk.next_cut(walk.gap_end(b, 1), 1)) {
            cuts.push_back(b);
        }
    }
    return cuts;
}

/// Splits the points of a merged blob along the unit direction (dir_x, dir_z) into pieces of
/// about `prior_m`, cutting at the emptiest place near each even cut (touching parked cars).
/// With `from_near_end`, the cuts are walked from the end nearer the camera instead, each at
/// the emptiest place about `prior_m` beyond the previous one: the far end of a long row is
/// seen sparsely, so its extent (and an even division of it) is unreliable. With `tall`, a thing
/// whose points within `prior_m` of the walk's last cut reach its height has its pitch instead
/// (a van's length, not a car's: a cut one car length on falls inside the van) where no clear
/// gap lies within reach of one `prior_m` on, or where a wider one lies within reach of its
/// pitch (gaps measured with single-bin islands of stray points merged).
Split split_along(const std::vector<Eigen::Vector3f>& pts, const Indices& idx, double dir_x,
                  double dir_z, double extent_m, double prior_m, bool from_near_end = false,
                  const TallPitch* tall = nullptr) {
    const int pieces = std::max(2, static_cast<int>(std::lround(extent_m / prior_m)));
    const Projection p = project(pts, idx, dir_x, dir_z);
    const Density density = density_along(p);
    Split split;
    split.at_gaps = true;
    std::vector<double> cuts;
    const int reach = static_cast<int>(0.25 * prior_m / kSplitBin);
    const int step = static_cast<int>(std::lround(prior_m / kSplitBin));
    const auto add_cut = [&](int best) {
        cuts.push_back(p.lo + (best + 0.5) * kSplitBin);
        if (!density.is_gap(best)) split.at_gaps = false;
    };
    if (from_near_end) {
        for (int b : walk_from_near_end(pts, idx, p, density, step, reach, tall)) add_cut(b);
    }
    const double piece = (p.hi - p.lo) / pieces;
    for (int k = 1; k < pieces && !from_near_end; ++k) {
        add_cut(density.emptiest(static_cast<int>(k * piece / kSplitBin), reach));
    }
    std::sort(cuts.begin(), cuts.end());
    split.parts.resize(cuts.size() + 1);
    for (std::size_t k = 0; k < idx.size(); ++k) {
        const auto part = static_cast<std::size_t>(
            std::upper_bound(cuts.begin(), cuts.end(), p.along[k]) - cuts.begin());
        split.parts[part].push_back(idx[k]);
    }
    return split;
}

/// Two pieces of a blob cut along the unit direction (dir_x, dir_z) in its widest clear gap
/// (a run of at least min_gap_bins 0.1 m bins each holding at most a quarter of the median
/// occupied bin's points) that leaves each piece at least a fifth of the points (a sliver or
/// a sparse far side is no second thing), or at least min_piece points when that is set, and
/// whose pieces overlap along the cut by at least min_overlap_m; nothing when there is no such
/// gap. With max_near_piece_m > 0 the piece at the end of the blob nearer the camera (along
/// the direction) must be at most that long.
std::optional<Split> split_at_gap(const std::vector<Eigen::Vector3f>& pts, const Indices& idx,
                                  double dir_x, double dir_z, int min_gap_bins,
                                  double min_extent_m = 0.0, int* gap_bins = nullptr,
                                  std::size_t min_piece = 0,
                                  double min_overlap_m = kSideBySideOverlap,
                                  double max_near_piece_m = 0.0) {
    if (idx.size() < 20) return std::nullopt;
    const Projection p = project(pts, idx, dir_x, dir_z);
    const std::vector<double>& along = p.along;
    const double lo = p.lo, hi = p.hi;
    if (hi - lo < min_extent_m) return std::nullopt;
    constexpr double kBin = 0.1;
    const int bins = static_cast<int>((hi - lo) / kBin) + 1;
    std::vector<std::size_t> hist(static_cast<std::size_t>(bins), 0);
    for (double a : along) ++hist[static_cast<std::size_t>((a - lo) / kBin)];
    std::vector<std::size_t> occupied;
    for (std::size_t h : hist) {
        if (h > 0) occupied.push_back(h);
    }
    std::nth_element(occupied.begin(), occupied.begin() + occupied.size() / 2, occupied.end());
    const double gap_count = kGapFraction * static_cast<double>(occupied[occupied.size() / 2]);
    const std::size_t total = idx.size();
    std::size_t before = 0;  // points in the bins before b
    int best_width = 0;
    double best_cut = 0.0;
    for (int b = 0; b < bins;) {
        if (static_cast<double>(hist[static_cast<std::size_t>(b)]) > gap_count) {
            before += hist[static_cast<std::size_t>(b++)];
            continue;
        }
        int end = b;  // one past the run of gap bins
        std::size_t inside = 0;
        while (end < bins && static_cast<double>(hist[static_cast<std::size_t>(end)]) <= gap_count)
            inside += hist[static_cast<std::size_t>(end++)];
        const std::size_t left = before + inside / 2, right = total - left;
        const bool pieces = min_piece > 0 ? std::min(left, right) >= min_piece
                                          : 5 * left >= total && 5 * right >= total;
        const double cut = lo + 0.5 * (b + end) * kBin;
        const double near_piece = std::abs(lo) < std::abs(hi) ? cut - lo : hi - cut;
        const bool near_fits = !(max_near_piece_m > 0.0) || near_piece <= max_near_piece_m;
        if (end - b >= min_gap_bins && end - b > best_width && pieces && near_fits) {
            best_width = end - b;
            best_cut = cut;
        }
        before += inside;
        b = end;
    }
    if (best_width == 0) return std::nullopt;
    Split split;
    split.at_gaps = true;
    split.parts.resize(2);
    // Side by side, the two overlap along the cut (a gap seen obliquely between two things
    // end to end does not): their 5-95 % extents along it share at least kSideBySideOverlap.
    std::array<std::vector<double>, 2> along_cut;
    for (std::size_t k = 0; k < idx.size(); ++k) {
        const int side = along[k] < best_cut ? 0 : 1;
        split.parts[side].push_back(idx[k]);
        along_cut[side].push_back(-double{pts[idx[k]].x()} * dir_z +
                                  double{pts[idx[k]].z()} * dir_x);
    }
    const auto [lo0, hi0] = quantiles(along_cut[0], 0.05, 0.95);
    const auto [lo1, hi1] = quantiles(along_cut[1], 0.05, 0.95);
    if (std::min(hi0, hi1) - std::max(lo0, lo1) < min_overlap_m) return std::nullopt;
    if (gap_bins) *gap_bins = best_width;
    return split;
}

/// Things side by side (a car passing a parked one): a clear gap that leaves each side a
/// real share of the points parts them before any reading of the blob as one row. Looked
/// for across the box's heading, when the box is wider than one thing, and across the
/// viewing ray, where stereo keeps gaps open, for a box that took a heading between the
/// two things' (their faces at an angle to it): seven directions within 30 degrees of
/// across the ray to the box. The widest gap of all wins. (Any direction cuts the rows of
/// parked streets apart at random; a single direction across the ray mixes the long faces
/// of two cars side by side.)
std::optional<Split> split_side_by_side(const std::vector<Eigen::Vector3f>& pts, const Indices& idx,
                                        const OrientedBox& box, const ClassSettings& s) {
    const double min_width = kSideBySideWidth * s.prior_W_m;
    std::optional<Split> widest;
    int widest_bins = 0;
    // The widest clear gap across the unit direction (dir_x, dir_z) so far.
    const auto consider = [&](double dir_x, double dir_z, double min_extent) {
        int bins = 0;
        auto cut = split_at_gap(pts, idx, dir_x, dir_z, kSideBySideGapBins, min_extent, &bins);
        if (cut && bins > widest_bins) {
            widest = std::move(cut);
            widest_bins = bins;
        }
    };
    // Angle a from +z towards +x: the direction (sin a, cos a).
    if (box.W_m > min_width) consider(std::sin(box.theta), std::cos(box.theta), 0.0);
    const double ray = std::atan2(box.centre_m.x(), box.centre_m.z());  // from +z towards +x
    for (int k = -3; k <= 3; ++k) {
        const double a = ray + kHalfPi + k * kHalfPi / 9.0;
        consider(std::sin(a), std::cos(a), min_width);
    }
    return widest;
}

/// Things in line: the widest clear gap within 20 degrees of the box's heading (which smear
/// skews), each piece holding at least a thing's minimum of points (and the piece nearer
/// the camera at most max_near_m long, when that is set).
std::optional<Split> split_in_line(const std::vector<Eigen::Vector3f>& pts, const Indices& idx,
                                   const OrientedBox& box, const ClassSettings& s,
                                   double max_near_m = 0.0) {
    std::optional<Split> cut;
    int cut_bins = 0;
    for (int k = -4; k <= 4; ++k) {
        const double a = box.theta + k * kHalfPi / 18.0;  // a heading: along (cos, -sin)
        int bins = 0;
        auto piece =
            split_at_gap(pts, idx, std::cos(a), -std::sin(a), kSideBySideGapBins, 0.0, &bins,
                         static_cast<std::size_t>(s.min_points), kInLineOverlap, max_near_m);
        if (piece && bins > cut_bins) {
            cut = std::move(piece);
            cut_bins = bins;
        }
    }
    return cut;
}

/// Whether a cut along the box's heading parts a piece of a van's height from one lower, or
/// two lower pieces that each hold a roof (see split_oversized).
bool parts_van_or_roofs(const std::vector<Eigen::Vector3f>& pts, const Split& cut,
                        const OrientedBox& box, const ClassSettings& s, const GroundPlane& ground,
                        const ExtractOptions& options) {
    const double c = std::cos(box.theta), sn = std::sin(box.theta);
    int tall_pieces = 0, roofed_pieces = 0;
    for (const Indices& part : cut.parts) {
        if (part.empty()) continue;
        std::vector<double> h;
        h.reserve(part.size());
        for (const auto k : part) h.push_back(ground.height(pts[k].cast<double>()));
        const double top = quantile(h, 0.98);
        std::vector<double> along = project(pts, part, c, -sn).along;
        const auto [first, last] = quantiles(along, 0.02, 0.98);
        if (top >= options.van_min_height_m) ++tall_pieces;
        if (top >= options.row_valley_min_peak_fraction * s.prior_H_m &&
            last - first >= 0.5 * s.prior_L_m) {
            ++roofed_pieces;
        }
    }
    return tall_pieces == 1 || (tall_pieces == 0 && roofed_pieces == 2);
}

}  // namespace

/// Vertical extent of points (2 % to 98 % height quantiles above the ground, or along -y
/// without a ground plane), metres.
double height_spread(const std::vector<Eigen::Vector3f>& pts, const Indices& idx,
                     const std::optional<GroundPlane>& ground) {
    std::vector<double> h;
    h.reserve(idx.size());
    for (std::size_t i : idx) {
        h.push_back(ground ? ground->height(pts[i].cast<double>()) : -double{pts[i].y()});
    }
    const auto [lo, hi] = quantiles(h, 0.02, 0.98);
    return hi - lo;
}

/// Pieces of a thing whose box is much longer or wider than its prior (a parked row, or
/// cars side by side merged by the semantic image); {idx} when it fits the prior.
Split split_oversized(const std::vector<Eigen::Vector3f>& pts, const Indices& idx,
                      const OrientedBox& box, const ClassSettings& s,
                      const std::optional<GroundPlane>& ground, const ExtractOptions& options,
                      bool truncated, bool row_piece) {
    if (!s.has_prior()) return {{idx}, false, std::nullopt};
    // The partition's length model is the size family's (cars and vans); other classes keep
    // the rules.
    const bool partition = options.row_model == "partition" && !options.family_class.empty() &&
                           s.name == options.family_class;
    const double c = std::cos(box.theta), sn = std::sin(box.theta);
    if (std::optional<Split> widest = split_side_by_side(pts, idx, box, s)) return *widest;
    // A piece of a row's partition is one thing parked along the row, not a row across it.
    if (ground && options.row_low_fraction > 0.0 && !(partition && row_piece) &&
        front_on_row(pts, idx, box, s, *ground, options)) {
        // Side by side: cut along the box's length at the row's pitch; each piece heads across.
        Split split = split_along(pts, idx, c, -sn, box.L_m, s.prior_W_m + options.row_gap_m, true);
        split.yaw_rad = wrap_angle(box.theta + kHalfPi);
        split.at_gaps = true;  // a row of distinct things, whatever the density at the cuts
        return split;
    }
    if (partition && ground && (!row_piece || box.L_m > s.split_factor * s.prior_L_m) &&
        box.L_m > options.row_valley_min_length_fraction * s.prior_L_m) {
        // Parked end to end: the row's partition, once per blob, and again for a piece that
        // came out longer than a row's split length (it holds points past the profile's end).
        const double centre = box.centre_m.x() * c - box.centre_m.z() * sn;
        bool apart = false;
        std::vector<Indices> parts =
            partition_row(pts, idx, c, -sn, centre, box.L_m, s, *ground, options, truncated, apart);
        // One thing with what is no thing's left out is a partition too: it is fitted again.
        if (parts.size() > 1 || (parts.size() == 1 && parts.front().size() < idx.size())) {
            return {std::move(parts), apart, std::nullopt, true};
        }
    }
    if (!partition && ground && options.row_valley_depth_m > 0.0 &&
        box.L_m > options.row_valley_min_length_fraction * s.prior_L_m) {
        // Parked end to end: cut where the evidence says, at the valleys between the roofs.
        std::vector<Indices> parts = split_at_valleys(pts, idx, c, -sn, s, *ground, options);
        if (parts.size() > 1) return {std::move(parts), false, std::nullopt};
    }
    const double van_pitch = options.van_prior_L_m + options.row_gap_m;
    if (!partition && ground && s.name == options.family_class && box.L_m > van_pitch &&
        box.L_m <= s.split_factor * s.prior_L_m) {
        // Longer than a van and its gap, too short for a row's walk: a van and the car before or
        // after it (a small car's low end keeps the two under a van's height and their valley
        // too shallow), or a van holding the end of the next car; or two small cars end to end,
        // smear filling the valley between their roofs. A clear gap parts a piece of a van's
        // height from one lower, or two lower pieces that each hold a roof: a top at the
        // valley cut's peak height over half a car's length. One car seen long by smear has
        // holes of the disparity's sub-pixel steps too, but they leave a short or low piece
        // (its bonnet or its boot) beyond them.
        if (const std::optional<Split> cut = split_in_line(pts, idx, box, s)) {
            if (parts_van_or_roofs(pts, *cut, box, s, *ground, options)) return *cut;
        }
    }
    if ((!partition || !ground) && box.L_m > s.split_factor * s.prior_L_m) {
        // Parked end to end: walk the gaps from the near end when there are gaps (the far end
        // is seen sparsely, so its extent is unreliable); touching things are cut evenly.
        std::optional<TallPitch> tall;
        if (ground && s.name == options.family_class) {
            tall = TallPitch{*ground, options.van_min_height_m, van_pitch};
        }
        Split walk = split_along(pts, idx, c, -sn, box.L_m, s.prior_L_m + options.row_gap_m, true,
                                 tall ? &*tall : nullptr);
        if (walk.at_gaps && walk.parts.size() > 1) return walk;
        return split_along(pts, idx, c, -sn, box.L_m, s.prior_L_m);
    }
    if (truncated && box.L_m > options.row_valley_min_length_fraction * s.prior_L_m) {
        // The image's edge cuts the thing: what shows of it is at most its own length, so a
        // longer blob holds a second thing beyond it, parted by a clear gap along the row
        // (the two in line, their sides seen edge-on as thin as they are) that leaves the cut
        // thing, the piece nearer the camera, no longer than that: a wider gap farther on (a
        // sliver of smear beyond the second thing) would leave both in one piece.
        if (std::optional<Split> cut = split_in_line(
                pts, idx, box, s, options.row_valley_min_length_fraction * s.prior_L_m)) {
            return std::move(*cut);
        }
    }
    // Across the heading only for a clear double width: smear and oblique views widen single cars.
    if (box.W_m > std::max(s.split_factor, 1.9) * s.prior_W_m) {
        return split_along(pts, idx, sn, c, box.W_m, s.prior_W_m);
    }
    return {{idx}, false, std::nullopt};
}

std::vector<Indices> join_faint_pieces(const std::vector<Eigen::Vector3f>& pts,
                                       std::vector<Candidate>& candidates, const ClassSettings& s,
                                       const ExtractOptions& options) {
    const double min_m2 = min_seen_area_m2(s, options);
    if (!(min_m2 > 0.0) || candidates.size() < 2) return {};
    std::vector<double> area(candidates.size());
    std::vector<char> joined(candidates.size(), 0);
    for (std::size_t i = 0; i < candidates.size(); ++i) {
        area[i] = thing_seen_area_m2(pts, candidates[i].members, options);
    }
    const auto faint = [&](std::size_t i) { return area[i] < min_m2 && !joined[i]; };
    // 2-98 % extent of a piece along the unit direction (ax, az), and its median across.
    struct Extent {
        double lo, hi, across;
    };
    const auto extent = [&](const Indices& m, double ax, double az) {
        std::vector<double> along, across;
        along.reserve(m.size());
        across.reserve(m.size());
        for (std::size_t k : m) {
            along.push_back(double{pts[k].x()} * ax + double{pts[k].z()} * az);
            across.push_back(double{pts[k].x()} * az - double{pts[k].z()} * ax);
        }
        const auto [lo, hi] = quantiles(along, 0.02, 0.98);
        return Extent{lo, hi, quantile(across, 0.5)};
    };
    std::vector<Indices> out;
    for (std::size_t i = 0; i < candidates.size(); ++i) {
        if (!faint(i)) continue;
        const double ax = std::cos(candidates[i].box.theta),
                     az = -std::sin(candidates[i].box.theta);
        const Extent a = extent(candidates[i].members, ax, az);
        std::size_t best = candidates.size();
        double best_gap = std::numeric_limits<double>::max();
        for (std::size_t j = 0; j < candidates.size(); ++j) {
            if (j == i || !faint(j) || area[i] + area[j] < min_m2) continue;
            const Extent b = extent(candidates[j].members, ax, az);
            const double gap = std::max(b.lo - a.hi, a.lo - b.hi);
            if (gap > options.row_gap_m || gap >= best_gap ||
                std::abs(a.across - b.across) > 0.5 * s.prior_W_m ||
                std::max(a.hi, b.hi) - std::min(a.lo, b.lo) > s.prior_L_m) {
                continue;
            }
            best = j;
            best_gap = gap;
        }
        if (best == candidates.size()) continue;
        joined[i] = joined[best] = 1;
        Indices both = candidates[i].members;
        both.insert(both.end(), candidates[best].members.begin(), candidates[best].members.end());
        out.push_back(std::move(both));
    }
    if (out.empty()) return out;
    std::vector<Candidate> kept;
    for (std::size_t i = 0; i < candidates.size(); ++i) {
        if (!joined[i]) kept.push_back(std::move(candidates[i]));
    }
    candidates = std::move(kept);
    return out;
}

}  // namespace cloud_analysis::instances
