// A row of things parked end to end cut as one optimisation: the partition of its length whose
// pieces have the likeliest lengths and whose cuts lie in the deepest valleys of its top profile.

#include <algorithm>
#include <cmath>
#include <limits>

#include "cloud_analysis/support/select.hpp"
#include "row_split_internal.hpp"

namespace cloud_analysis::instances {
namespace {

/// Spread of the lengths of the things of one kind (cars of a class, vans), metres.
constexpr double kLengthSigmaM = 0.5;
/// Spread of a valley's depth about the depth at which two things meeting and one thing's dip
/// are alike (ExtractOptions::row_valley_depth_m), metres: a top profile's noise.
constexpr double kValleySigmaM = 0.15;
/// The most a cut's evidence counts, either way, in sigmas; a cut where the profile shows no
/// valley at all counts the least.
constexpr double kValleyCap = 3.0;
/// A dip of the top profile shallower than this is no valley, metres.
constexpr double kMinDipM = 0.1;
/// The fewest bins seen too sparsely for a top (or for a face: kSparseFraction) that make a
/// gap between two things.
constexpr int kMinGapBins = 2;
/// A bin holding less than this fraction of a typical bin's seen surface shows no thing's face
/// there: a gap between two things seen through to what is behind them.
constexpr double kSparseFraction = 0.1;
/// What leaving out a metre of a typical thing's seen surface costs, in log-likelihood: a
/// piece that holds no thing (a pole, a trunk, smear in a gap) is left out when it holds
/// little.
constexpr double kNothingPerMetre = 2.0;

/// A place the row may be cut: its along-coordinate from the row's start and the evidence, in
/// sigmas, that two things meet there.
struct CutSite {
    double at_m;
    double evidence;
};

/// The valleys of a top profile (bins of bin_m from the row's start) as cut sites: each run of
/// bins whose top lies at least kMinDipM below the highest tops within `reach` bins on both
/// sides (both reaching min_peak_m) is cut in the bin at the middle of the run's part below
/// half its depth (a boot and a bonnet flank the gap between them alike); its evidence is its
/// deepest bin's depth against `depth_m`, in kValleySigmaM.
std::vector<CutSite> valley_sites(const TopProfile& profile, double bin_m, int reach,
                                  double depth_m, double min_peak_m) {
    std::vector<CutSite> sites;
    for (const ValleyRun& run : valley_runs(profile.top, reach, kMinDipM, min_peak_m)) {
        const int at = static_cast<int>(std::lround(0.5 * (run.first + run.last)));
        const double evidence = (run.depth - depth_m) / kValleySigmaM;
        sites.push_back({(at + 0.5) * bin_m, std::clamp(evidence, -kValleyCap, kValleyCap)});
    }
    return sites;
}

/// The log-likelihood, relative to a thing of the likeliest length `mode_m`, of a thing of the
/// row being `length_m` long (a normal spread of kLengthSigmaM). A piece whose end is not seen
/// (the row's far end, hidden or beyond the profile, or a near end cut by the image's edge)
/// may be shorter than its thing.
double length_score(double length_m, bool may_be_short, double mode_m) {
    const double at = may_be_short ? std::max(length_m, mode_m) : length_m;
    const double d = (at - mode_m) / kLengthSigmaM;
    return -0.5 * d * d;
}

/// What a row's partition reads of its points, per bin of bin_m from lo.
struct RowEvidence {
    double lo = 0.0, bin_m = 0.15, length_m = 0.0;
    int bins = 0;
    TopProfile profile;
    std::vector<long> points_before;     ///< points in the bins before each bin
    long below = 0, beyond = 0;          ///< points before the first bin, after the last
    double first_m = 0.0, last_m = 0.0;  ///< the nearest and farthest point's along - lo
    std::vector<double> seen_before;     ///< seen surface (sum of z^2) before each bin
    std::vector<double> seen;            ///< per bin, its seen surface
    double typical_seen = 0.0;           ///< the median occupied bin's seen surface
    std::vector<int> next_seen;          ///< the first bin with a top from b on
    /// The first bin from b on, and the last one before b, with a top and a face (at least
    /// kSparseFraction of a typical bin's seen surface): a thing's length runs between its own.
    std::vector<int> next_face, prev_face;
    std::vector<double> gap_at_m;  ///< the middle of each gap inside the row
    std::vector<int> gaps_before;  ///< gaps whose middle lies in the bins before b

    /// The gaps whose middle lies inside bins (b0, b1): a thing holding one would be two.
    int gaps_inside(int b0, int b1) const {
        if (b1 <= b0 + 1) return 0;
        return gaps_before[static_cast<std::size_t>(b1)] -
               gaps_before[static_cast<std::size_t>(b0 + 1)];
    }

    int bin_of(double at_m, bool end) const {
        return end ? bins : std::clamp(static_cast<int>(at_m / bin_m), 0, bins);
    }
    long points(int b0, int b1) const {
        return points_before[static_cast<std::size_t>(b1)] -
               points_before[static_cast<std::size_t>(b0)];
    }
    /// Metres of a typical bin's surface held in bins [b0, b1).
    double seen_metres(int b0, int b1) const {
        if (!(typical_seen > 0.0)) return 0.0;
        return (seen_before[static_cast<std::size_t>(b1)] -
                seen_before[static_cast<std::size_t>(b0)]) /
               typical_seen * bin_m;
    }
};

/// The row's gaps: runs of kMinGapBins bins or more inside it, each seen too sparsely for a top
/// or holding under kSparseFraction of a typical bin's seen surface (what is behind two things
/// seen between them).
void find_gaps(RowEvidence& r) {
    const double sparse = kSparseFraction * r.typical_seen;
    const auto gap = [&](int b) {
        return r.profile.top[static_cast<std::size_t>(b)] < 0.0 ||
               r.seen[static_cast<std::size_t>(b)] < sparse;
    };
    r.gaps_before.assign(static_cast<std::size_t>(r.bins) + 1, 0);
    std::vector<int> mid_count(static_cast<std::size_t>(r.bins), 0);
    for (int b = 0; b < r.bins;) {
        if (!gap(b)) {
            ++b;
            continue;
        }
        int end = b;
        while (end < r.bins && gap(end)) ++end;
        if (b > 0 && end < r.bins && end - b >= kMinGapBins) {
            r.gap_at_m.push_back(0.5 * (b + end) * r.bin_m);
            ++mid_count[static_cast<std::size_t>((b + end) / 2)];
        }
        b = end;
    }
    for (std::size_t b = 0; b < mid_count.size(); ++b) {
        r.gaps_before[b + 1] = r.gaps_before[b] + mid_count[b];
    }
}

RowEvidence row_evidence(const std::vector<Eigen::Vector3f>& pts, const Indices& idx,
                         const std::vector<double>& along, const GroundPlane& ground, double lo,
                         double hi, const ExtractOptions& options) {
    RowEvidence r;
    r.lo = lo;
    r.bin_m = options.row_valley_bin_m;
    r.length_m = hi - lo;
    r.last_m = r.length_m;
    const int closing = static_cast<int>(std::lround(options.row_valley_closing_m / r.bin_m));
    r.profile = top_profile(pts, idx, along, ground, r.bin_m, lo, hi, closing);
    r.bins = static_cast<int>(r.profile.top.size());
    const auto nb = static_cast<std::size_t>(r.bins);
    r.seen.assign(nb, 0.0);
    for (std::size_t k = 0; k < idx.size(); ++k) {
        const int b = static_cast<int>(std::floor((along[k] - lo) / r.bin_m));
        r.first_m = std::min(r.first_m, along[k] - lo);
        r.last_m = std::max(r.last_m, along[k] - lo);
        r.below += b < 0 ? 1 : 0;
        r.beyond += b >= r.bins ? 1 : 0;
        if (b < 0 || b >= r.bins) continue;
        const double z = pts[idx[k]].z();
        r.seen[static_cast<std::size_t>(b)] += z * z;
    }
    r.points_before.assign(nb + 1, 0);
    r.seen_before.assign(nb + 1, 0.0);
    std::vector<double> occupied;
    for (std::size_t b = 0; b < nb; ++b) {
        r.points_before[b + 1] = r.points_before[b] + r.profile.count[b];
        r.seen_before[b + 1] = r.seen_before[b] + r.seen[b];
        if (r.profile.top[b] >= 0.0) occupied.push_back(r.seen[b]);
    }
    if (!occupied.empty()) r.typical_seen = quantile(occupied, 0.5);
    r.next_seen.assign(nb + 1, r.bins);
    r.next_face.assign(nb + 1, r.bins);
    r.prev_face.assign(nb + 1, -1);
    const auto face = [&](std::size_t k) {
        return r.profile.top[k] >= 0.0 && r.seen[k] >= kSparseFraction * r.typical_seen;
    };
    for (int b = r.bins - 1; b >= 0; --b) {
        const auto k = static_cast<std::size_t>(b);
        r.next_seen[k] = r.profile.top[k] >= 0.0 ? b : r.next_seen[k + 1];
        r.next_face[k] = face(k) ? b : r.next_face[k + 1];
    }
    for (std::size_t b = 1; b <= nb; ++b) {
        r.prev_face[b] = face(b - 1) ? static_cast<int>(b) - 1 : r.prev_face[b - 1];
    }
    find_gaps(r);
    return r;
}

/// Where the row may be cut: its valleys, its gaps (a run of kMinGapBins bins seen too
/// sparsely for a top, inside the row: the most evidence, at its middle) and every bin (the
/// least: things may touch where no valley shows); last, the row's end.
std::vector<CutSite> cut_sites(const RowEvidence& row, const ClassSettings& s,
                               const ExtractOptions& options) {
    const int reach = std::max(1, static_cast<int>(std::lround(0.5 * s.prior_L_m / row.bin_m)));
    std::vector<CutSite> sites =
        valley_sites(row.profile, row.bin_m, reach, options.row_valley_depth_m,
                     options.row_valley_min_peak_fraction * s.prior_H_m);
    for (const double at : row.gap_at_m) sites.push_back({at, kValleyCap});
    for (int b = 0; b < row.bins; ++b) sites.push_back({(b + 0.5) * row.bin_m, -kValleyCap});
    std::sort(sites.begin(), sites.end(),
              [](const CutSite& a, const CutSite& b) { return a.at_m < b.at_m; });
    sites.push_back({row.length_m, 0.0});
    return sites;
}

/// The points of the thing pieces of the best partition (sites, from, thing: partition_row);
/// `apart` whether every two things that meet do so where the evidence says (a gap or a
/// valley), not merely at their lengths.
std::vector<Indices> pieces_of(const std::vector<CutSite>& sites, const std::vector<long>& from,
                               const std::vector<char>& thing, const std::vector<double>& along,
                               const Indices& idx, double lo, bool& apart) {
    struct Piece {
        double begin, end;
    };
    std::vector<Piece> kept;
    const double inf = std::numeric_limits<double>::infinity();
    std::size_t count = 0;
    apart = true;
    for (long j = static_cast<long>(sites.size()) - 1; j >= 0;
         j = from[static_cast<std::size_t>(j)]) {
        ++count;
        const long i = from[static_cast<std::size_t>(j)];
        if (!thing[static_cast<std::size_t>(j)]) continue;
        if (i >= 0 && thing[static_cast<std::size_t>(i)] &&
            !(sites[static_cast<std::size_t>(i)].evidence > 0.0)) {
            apart = false;
        }
        const bool last = j + 1 == static_cast<long>(sites.size());
        kept.push_back({i < 0 ? -inf : lo + sites[static_cast<std::size_t>(i)].at_m,
                        last ? inf : lo + sites[static_cast<std::size_t>(j)].at_m});
    }
    if (count < 2) return {};
    std::vector<Indices> parts(kept.size());
    for (std::size_t k = 0; k < idx.size(); ++k) {
        for (std::size_t p = 0; p < kept.size(); ++p) {
            if (along[k] >= kept[p].begin && along[k] < kept[p].end) {
                parts[p].push_back(idx[k]);
                break;
            }
        }
    }
    parts.erase(
        std::remove_if(parts.begin(), parts.end(), [](const Indices& p) { return p.empty(); }),
        parts.end());
    return parts;
}

}  // namespace

std::vector<Indices> partition_row(const std::vector<Eigen::Vector3f>& pts, const Indices& idx,
                                   double dir_x, double dir_z, double centre_along, double length_m,
                                   const ClassSettings& s, const GroundPlane& ground,
                                   const ExtractOptions& options, bool near_end_cut, bool& apart) {
    const double min_piece = options.row_valley_min_piece_m;
    apart = false;
    if (idx.size() < 20 || length_m < 2.0 * min_piece) return {};
    const std::vector<double> along = project(pts, idx, dir_x, dir_z).along;
    // The profile spans the fitted box and the points beyond its far end (a sparse thing
    // farther on that the box's fit left out); the pieces' lengths are what each holds of it.
    std::vector<double> sorted = along;
    const auto [q_lo, q_hi] = quantiles(sorted, 0.005, 0.995);
    double lo = centre_along - 0.5 * length_m, hi = centre_along + 0.5 * length_m;
    const bool near_is_lo = std::abs(lo) <= std::abs(hi);
    if (near_is_lo) {
        hi = std::max(hi, q_hi);
    } else {
        lo = std::min(lo, q_lo);
    }
    const RowEvidence row = row_evidence(pts, idx, along, ground, lo, hi, options);
    const std::vector<CutSite> sites = cut_sites(row, s, options);
    const double min_roof = options.row_valley_min_peak_fraction * s.prior_H_m;
    const auto min_points = static_cast<long>(std::max(s.min_points / 2, 1));
    const std::size_t n = sites.size();
    // best[j]: the best score of the pieces from the row's start to site j; from[j] the site
    // before (-1: the start) and whether the piece between is a thing.
    std::vector<double> best(n, -std::numeric_limits<double>::infinity());
    std::vector<long> from(n, -1);
    std::vector<char> thing(n, 0);
    for (std::size_t j = 0; j < n; ++j) {
        const bool last = j + 1 == n;
        const int end_bin = row.bin_of(sites[j].at_m, last);
        double roof = -1.0;       // the highest top of bins [roof_from, end_bin)
        int roof_from = end_bin;  // (the sites run backwards from j: it only grows)
        for (long i = static_cast<long>(j) - 1; i >= -1; --i) {
            const double before = i < 0 ? 0.0 : best[static_cast<std::size_t>(i)];
            if (!std::isfinite(before)) continue;
            const double start = i < 0 ? 0.0 : sites[static_cast<std::size_t>(i)].at_m;
            const int start_bin = row.bin_of(start, false);
            if (end_bin <= start_bin) continue;
            for (; roof_from > start_bin; --roof_from) {
                roof = std::max(roof, row.profile.top[static_cast<std::size_t>(roof_from - 1)]);
            }
            const double cut = before + sites[j].evidence;
            // Nothing: what it holds is no thing's (a pole, a trunk, smear in a gap); the
            // evidence of things meeting at its end does not count for it.
            const double nothing = before - kNothingPerMetre * row.seen_metres(start_bin, end_bin);
            if (nothing > best[j]) {
                best[j] = nothing;
                from[j] = i;
                thing[j] = 0;
            }
            const int first_seen = row.next_seen[static_cast<std::size_t>(start_bin)];
            const int first_face = row.next_face[static_cast<std::size_t>(start_bin)];
            const int last_face = row.prev_face[static_cast<std::size_t>(end_bin)];
            // The end pieces also span and hold the points past the profile's ends.
            const double span = (last ? std::max(sites[j].at_m, row.last_m) : sites[j].at_m) -
                                (i < 0 ? std::min(start, row.first_m) : start);
            if (first_seen >= end_bin || span < min_piece) continue;
            const long held =
                row.points(start_bin, end_bin) + (i < 0 ? row.below : 0) + (last ? row.beyond : 0);
            if (roof < min_roof || held < min_points) continue;
            const bool at_near = near_is_lo ? i < 0 : last;
            const bool at_far = near_is_lo ? last : i < 0;
            // A piece reaching a van's height is a van, of a van's length; any other, a car of
            // its class's. Its length is what it holds of the row.
            const double mode =
                roof >= options.van_min_height_m ? options.van_prior_L_m : s.prior_L_m;
            const double score = cut - kValleyCap * row.gaps_inside(start_bin, end_bin) +
                                 length_score(std::max(0, last_face - first_face + 1) * row.bin_m,
                                              at_far || (at_near && near_end_cut), mode);
            if (score > best[j]) {
                best[j] = score;
                from[j] = i;
                thing[j] = 1;
            }
        }
    }
    return pieces_of(sites, from, thing, along, idx, row.lo, apart);
}

}  // namespace cloud_analysis::instances
