// A blob's height profiles as evidence of a row: the low bonnets across things side by side seen
// front-on, and the valleys between the roofs of things parked end to end.

#include <algorithm>
#include <cmath>
#include <limits>
#include <numeric>

#include "cloud_analysis/support/select.hpp"
#include "row_split_internal.hpp"

namespace cloud_analysis::instances {
namespace {

/// How far, from the camera's side, the tops (95 % height per 0.1 m bin across, bins of at
/// least 5 points) of the points `members` (indices into across / heights) stay below
/// low_fraction * their highest top, metres; -1 when fewer than 3 bins are known.
double low_extent_m(const std::vector<std::size_t>& members, const std::vector<double>& across,
                    const std::vector<double>& heights, double lo, double hi, bool near_is_lo,
                    double low_fraction) {
    constexpr double kBin = 0.1;
    constexpr std::size_t kMinBinPoints = 5;
    const int bins = static_cast<int>((hi - lo) / kBin) + 1;
    if (bins < 3) return -1.0;
    std::vector<std::vector<double>> in_bin(static_cast<std::size_t>(bins));
    for (std::size_t k : members) {
        const int b = static_cast<int>((across[k] - lo) / kBin);
        if (b < 0 || b >= bins) continue;
        in_bin[static_cast<std::size_t>(b)].push_back(heights[k]);
    }
    std::vector<double> top(static_cast<std::size_t>(bins), -1.0);
    double highest = 0.0;
    int known = 0;
    for (int b = 0; b < bins; ++b) {
        auto& h = in_bin[static_cast<std::size_t>(b)];
        if (h.size() < kMinBinPoints) continue;
        top[static_cast<std::size_t>(b)] = quantile(h, 0.95);
        highest = std::max(highest, top[static_cast<std::size_t>(b)]);
        ++known;
    }
    if (highest <= 0.0 || known < 3) return -1.0;
    double low = 0.0;
    int first = -1;  // the first known bin from the near side: the extent starts there
    for (int k = 0; k < bins; ++k) {
        const double t = top[static_cast<std::size_t>(near_is_lo ? k : bins - 1 - k)];
        if (t < 0.0) continue;
        if (first < 0) first = k;
        if (t >= low_fraction * highest) break;
        low = (k - first + 1) * kBin;
    }
    return low;
}

/// The cuts (along-coordinates) of a blob at the valleys of its top profile: a thing is a hump
/// (a car's roof over its lower bonnet and boot), so where the top drops at least depth_m below
/// the highest top on both sides within `reach` bins, and both those tops reach min_peak_m,
/// two things meet. Each valley is cut at the emptiest bin of its part below half its depth
/// (the gap between the two; the one nearest that part's middle among equals): a profile's
/// shape is smeared along the viewing ray, the gap's emptiness less so. Cuts closer than
/// min_piece_m to an end or to a deeper cut are dropped.
std::vector<double> valley_cuts(const TopProfile& profile, double lo, double bin_m, int reach,
                                double depth_m, double min_peak_m, double min_piece_m) {
    const int bins = static_cast<int>(profile.top.size());
    struct Valley {
        double at, depth;
    };
    std::vector<Valley> valleys;
    for (const ValleyRun& run : valley_runs(profile.top, reach, depth_m, min_peak_m)) {
        const int first = run.first, last = run.last;
        // Cut at its emptiest bin (the gap), the one nearest its middle among equals.
        const double middle = 0.5 * (first + last);
        int at = run.deepest;
        for (int k = first; k <= last; ++k) {
            const int nk = profile.count[static_cast<std::size_t>(k)];
            const int na = profile.count[static_cast<std::size_t>(at)];
            if (nk < na || (nk == na && std::abs(k - middle) < std::abs(at - middle))) at = k;
        }
        valleys.push_back({lo + (at + 0.5) * bin_m, run.depth});
    }
    // Deepest first, each kept when it leaves pieces of at least min_piece_m.
    std::sort(valleys.begin(), valleys.end(),
              [](const Valley& a, const Valley& c) { return a.depth > c.depth; });
    const double hi = lo + bins * bin_m;
    std::vector<double> cuts;
    for (const Valley& v : valleys) {
        bool fits = v.at - lo >= min_piece_m && hi - v.at >= min_piece_m;
        for (double c : cuts) fits = fits && std::abs(c - v.at) >= min_piece_m;
        if (fits) cuts.push_back(v.at);
    }
    std::sort(cuts.begin(), cuts.end());
    return cuts;
}

/// The cuts of a valley split (sorted along-coordinates of a profile starting at lo in bins of
/// bin_m) moved off the dense run that a piece holds at one of its cuts when the rest of the
/// piece is sparse: a piece that is mostly a gap (smear and label bleed at a tree or a pole
/// between two parked cars, whose few high points make a hump of it) with the first or last
/// metre of a car beside it. The run (the bins from the cut on holding at least a quarter of
/// the densest within kSnapRunM of the cut, at most kSnapRunM long) joins the piece beyond the
/// cut, which is where its car is, when every bin of the rest, kSnapGapM long or more, holds
/// less than that quarter. The gap's piece keeps only its sparse points.
void snap_cuts_off_runs(const TopProfile& profile, double lo, double bin_m,
                        std::vector<double>& cuts) {
    constexpr double kSnapRunM = 1.5;  // longest run moved: the end of a car, not a car
    constexpr double kSnapGapM = 1.0;  // shortest sparse rest: a gap, not a sparse car end
    const int bins = static_cast<int>(profile.count.size());
    const int run_bins = static_cast<int>(kSnapRunM / bin_m);
    const auto bin_of = [&](double a) {
        return std::clamp(static_cast<int>((a - lo) / bin_m), 0, bins - 1);
    };
    const auto count = [&](int b) { return profile.count[static_cast<std::size_t>(b)]; };
    for (std::size_t k = 0; k <= cuts.size(); ++k) {
        const int b0 = k == 0 ? 0 : bin_of(cuts[k - 1]) + 1;
        const int b1 = k == cuts.size() ? bins - 1 : bin_of(cuts[k]);
        if (b1 - b0 < 2) continue;
        const auto inside = [&](int b) { return b >= b0 && b <= b1; };
        // Side 0: the run at the piece's far cut (cuts[k]); side 1: at its near cut (cuts[k-1]).
        for (int side = 0; side < 2; ++side) {
            if ((side == 0 && k == cuts.size()) || (side == 1 && k == 0)) continue;
            const int end = side == 0 ? b1 : b0, step = side == 0 ? -1 : 1;
            int peak = 0;
            for (int j = 0; j < run_bins && inside(end + step * j); ++j) {
                peak = std::max(peak, count(end + step * j));
            }
            const double floor = kGapFraction * peak;
            int r = end;
            while (inside(r + step) && count(r + step) >= floor) r += step;
            int rest_max = 0, rest = 0;
            for (int b = r + step; inside(b); b += step) {
                rest_max = std::max(rest_max, count(b));
                ++rest;
            }
            if (std::abs(r - end) + 1 <= run_bins && rest * bin_m >= kSnapGapM &&
                rest_max < floor) {
                if (side == 0) {
                    cuts[k] = lo + r * bin_m;
                } else {
                    cuts[k - 1] = lo + (r + 1) * bin_m;
                }
                break;
            }
        }
    }
    std::sort(cuts.begin(), cuts.end());
}

}  // namespace

std::vector<ValleyRun> valley_runs(const std::vector<double>& top, int reach, double min_depth_m,
                                   double min_peak_m) {
    const int bins = static_cast<int>(top.size());
    std::vector<ValleyRun> runs;
    int b = 0;
    while (b < bins) {
        // Deepest valley bin of a run of valley bins.
        int best = -1;
        double best_depth = 0.0, best_floor = 0.0;
        for (; b < bins; ++b) {
            const double t = top[static_cast<std::size_t>(b)];
            const double peak = flanking_peak(top, b, reach);
            const bool valley = t >= 0.0 && peak >= min_peak_m && peak - t >= min_depth_m;
            if (!valley) {
                if (best >= 0) break;
                continue;
            }
            if (best < 0 || peak - t > best_depth) {
                best = b;
                best_depth = peak - t;
                best_floor = t;
            }
        }
        if (best < 0) break;
        // The part of the valley below half its depth, unknown bins included.
        const double half = best_floor + 0.5 * best_depth;
        int first = best, last = best;
        while (first > 0 && top[static_cast<std::size_t>(first - 1)] < half) --first;
        while (last + 1 < bins && top[static_cast<std::size_t>(last + 1)] < half) ++last;
        runs.push_back({best, first, last, best_depth});
    }
    return runs;
}

double flanking_peak(const std::vector<double>& top, int b, int reach) {
    const int bins = static_cast<int>(top.size());
    double left = -1.0, right = -1.0;
    for (int k = std::max(0, b - reach); k < b; ++k) {
        left = std::max(left, top[static_cast<std::size_t>(k)]);
    }
    for (int k = b + 1; k <= std::min(bins - 1, b + reach); ++k) {
        right = std::max(right, top[static_cast<std::size_t>(k)]);
    }
    return std::min(left, right);
}

/// The top profile of the points idx (their along-coordinates `along`) in bins of bin_m from
/// lo to hi.
TopProfile top_profile(const std::vector<Eigen::Vector3f>& pts, const Indices& idx,
                       const std::vector<double>& along, const GroundPlane& ground, double bin_m,
                       double lo, double hi, int closing) {
    constexpr double kTopQuantile = 0.9;
    constexpr std::size_t kMinBinPoints = 3;
    const int bins = static_cast<int>((hi - lo) / bin_m) + 1;
    std::vector<std::vector<double>> heights(static_cast<std::size_t>(bins));
    for (std::size_t k = 0; k < idx.size(); ++k) {
        const int b = static_cast<int>((along[k] - lo) / bin_m);
        if (b < 0 || b >= bins) continue;
        heights[static_cast<std::size_t>(b)].push_back(ground.height(pts[idx[k]].cast<double>()));
    }
    std::vector<double> top(static_cast<std::size_t>(bins), -1.0);
    for (int b = 0; b < bins; ++b) {
        auto& h = heights[static_cast<std::size_t>(b)];
        if (h.size() >= kMinBinPoints) top[static_cast<std::size_t>(b)] = quantile(h, kTopQuantile);
    }
    // Narrow dips (a sparse bin, a window's reflection) are noise, not the ends of two things:
    // each known bin takes the highest known top within `closing` bins.
    std::vector<double> closed = top;
    for (int b = 0; b < bins; ++b) {
        if (top[static_cast<std::size_t>(b)] < 0.0) continue;
        for (int k = std::max(0, b - closing); k <= std::min(bins - 1, b + closing); ++k) {
            closed[static_cast<std::size_t>(b)] =
                std::max(closed[static_cast<std::size_t>(b)], top[static_cast<std::size_t>(k)]);
        }
    }
    std::vector<int> count(static_cast<std::size_t>(bins));
    for (int b = 0; b < bins; ++b) {
        count[static_cast<std::size_t>(b)] =
            static_cast<int>(heights[static_cast<std::size_t>(b)].size());
    }
    return {closed, count};
}

bool front_on_row(const std::vector<Eigen::Vector3f>& pts, const Indices& idx,
                  const OrientedBox& box, const ClassSettings& s, const GroundPlane& ground,
                  const ExtractOptions& options) {
    constexpr std::size_t kMinSlicePoints = 50;
    if (idx.size() < 20) return false;
    const double c = std::cos(box.theta), sn = std::sin(box.theta);
    std::vector<double> along, across, heights;
    along.reserve(idx.size());
    across.reserve(idx.size());
    double min_along = std::numeric_limits<double>::infinity(), max_along = -min_along;
    for (std::size_t i : idx) {
        along.push_back(double{pts[i].x()} * c - double{pts[i].z()} * sn);
        across.push_back(double{pts[i].x()} * sn + double{pts[i].z()} * c);
        min_along = std::min(min_along, along.back());
        max_along = std::max(max_along, along.back());
    }
    // The whole extent bounds the 2-98 % one: most blobs (single things) stop here.
    if (max_along - min_along < 2.0 * s.prior_W_m) return false;
    std::vector<double> sorted = along;
    const auto [along_lo, along_hi] = quantiles(sorted, 0.02, 0.98);
    if (along_hi - along_lo < 2.0 * s.prior_W_m) return false;
    sorted = across;
    const auto [lo, hi] = quantiles(sorted, 0.02, 0.98);
    const bool near_is_lo = std::abs(lo) <= std::abs(hi);
    heights.reserve(idx.size());
    for (std::size_t i : idx) heights.push_back(ground.height(pts[i].cast<double>()));
    std::vector<std::size_t> all(idx.size());
    std::iota(all.begin(), all.end(), std::size_t{0});
    if (low_extent_m(all, across, heights, lo, hi, near_is_lo, options.row_low_fraction) <
        options.row_low_extent_m) {
        return false;
    }
    const int slices = std::max(1, static_cast<int>((along_hi - along_lo) / s.prior_W_m));
    const double slice_m = (along_hi - along_lo) / slices;
    std::vector<std::vector<std::size_t>> in_slice(static_cast<std::size_t>(slices));
    for (std::size_t k = 0; k < along.size(); ++k) {
        const int j = static_cast<int>((along[k] - along_lo) / slice_m);
        if (j >= 0 && j < slices) in_slice[static_cast<std::size_t>(j)].push_back(k);
    }
    int seen = 0, low = 0;
    for (const auto& members : in_slice) {
        if (members.size() < kMinSlicePoints) continue;
        const double e =
            low_extent_m(members, across, heights, lo, hi, near_is_lo, options.row_low_fraction);
        if (e < 0.0) continue;
        ++seen;
        if (e >= options.row_low_extent_m) ++low;
    }
    return 2 * low >= seen;
}

std::vector<Indices> split_at_valleys(const std::vector<Eigen::Vector3f>& pts, const Indices& idx,
                                      double dir_x, double dir_z, const ClassSettings& s,
                                      const GroundPlane& ground, const ExtractOptions& options) {
    if (idx.size() < 20) return {};
    const std::vector<double> along = project(pts, idx, dir_x, dir_z).along;
    std::vector<double> sorted = along;
    const auto [lo, hi] = quantiles(sorted, 0.005, 0.995);
    const double bin = options.row_valley_bin_m;
    if (hi - lo < 2.0 * options.row_valley_min_piece_m) return {};
    const int closing = static_cast<int>(std::lround(options.row_valley_closing_m / bin));
    const TopProfile profile = top_profile(pts, idx, along, ground, bin, lo, hi, closing);
    const int reach = std::max(1, static_cast<int>(std::lround(0.5 * s.prior_L_m / bin)));
    std::vector<double> cuts = valley_cuts(profile, lo, bin, reach, options.row_valley_depth_m,
                                           options.row_valley_min_peak_fraction * s.prior_H_m,
                                           options.row_valley_min_piece_m);
    if (cuts.empty()) return {};
    snap_cuts_off_runs(profile, lo, bin, cuts);
    std::vector<Indices> parts(cuts.size() + 1);
    for (std::size_t k = 0; k < idx.size(); ++k) {
        const auto part = static_cast<std::size_t>(
            std::upper_bound(cuts.begin(), cuts.end(), along[k]) - cuts.begin());
        parts[part].push_back(idx[k]);
    }
    return parts;
}

}  // namespace cloud_analysis::instances
