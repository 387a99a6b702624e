#include "cloud_analysis/evaluation/track_eval.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <set>
#include <sstream>
#include <stdexcept>

#include "cloud_analysis/evaluation/kitti_labels.hpp"
#include "cloud_analysis/tracking/assignment.hpp"
#include "stereoscene/support/angles.hpp"

using stereoscene::support::wrap_angle;

namespace cloud_analysis {

namespace {

using stereoscene::support::kPi;
constexpr std::size_t kAllBins = kDistanceBinEdges_m.size();

double bev_distance(const scene_schema::Entity& a, const scene_schema::Entity& b) {
    return std::hypot(a.x - b.x, a.z - b.z);
}

double speed(const scene_schema::Entity& e) {
    return e.velocity ? std::hypot(e.velocity->vx_mps, e.velocity->vz_mps) : 0.0;
}

/// What the evaluation remembers of one class across frames.
struct ClassState {
    ClassTrackScore score;
    std::map<std::int64_t, std::int64_t> last_track;  ///< truth id -> track last matched
    std::map<std::int64_t, bool> covered;             ///< truth id -> matched when last owed
    std::map<std::pair<std::int64_t, std::int64_t>, std::size_t> overlap;  ///< IDTP candidates
    std::map<std::int64_t, std::size_t> truth_frames, track_frames;
    std::map<std::int64_t, double> last_theta;                  ///< track -> its previous heading
    std::map<std::int64_t, std::array<double, 6>> parked_size;  ///< track -> min/max W, H, L
    std::vector<HotaFrame> hota_frames;  ///< the scored truth and tracks of every frame
};

void count(TrackCounts& bin, TrackCounts& all, std::size_t TrackCounts::*field) {
    ++(bin.*field);
    ++(all.*field);
}

/// Per-frame CLEAR MOT matching of one class: (truth index, hypothesis index) pairs.
std::vector<std::pair<int, int>> match_frame(const std::vector<const TrackedObject*>& truth,
                                             const std::vector<const TrackedObject*>& hyps,
                                             const ClassState& state, double max_distance_m) {
    std::vector<std::pair<int, int>> pairs;
    std::vector<char> truth_done(truth.size(), 0), hyp_done(hyps.size(), 0);
    for (std::size_t t = 0; t < truth.size(); ++t) {
        const auto last = state.last_track.find(truth[t]->track_id);
        if (last == state.last_track.end()) continue;
        for (std::size_t h = 0; h < hyps.size(); ++h) {
            if (!hyp_done[h] && hyps[h]->track_id == last->second &&
                bev_distance(truth[t]->box, hyps[h]->box) <= max_distance_m) {
                pairs.emplace_back(static_cast<int>(t), static_cast<int>(h));
                truth_done[t] = hyp_done[h] = 1;
                break;
            }
        }
    }
    std::vector<int> rows, cols;
    for (std::size_t t = 0; t < truth.size(); ++t) {
        if (!truth_done[t]) rows.push_back(static_cast<int>(t));
    }
    for (std::size_t h = 0; h < hyps.size(); ++h) {
        if (!hyp_done[h]) cols.push_back(static_cast<int>(h));
    }
    tracking::CostMatrix m{static_cast<int>(rows.size()), static_cast<int>(cols.size()), {}};
    for (int r : rows) {
        for (int c : cols)
            m.cost.push_back(bev_distance(truth[r]->box, hyps[c]->box) / max_distance_m);
    }
    for (const auto& match : tracking::assign(m, 1.0))
        pairs.emplace_back(rows[match.row], cols[match.col]);
    return pairs;
}

TrackEvent event(TrackEvent::Kind kind, std::int64_t frame, const TrackedObject* truth,
                 const TrackedObject* hyp) {
    TrackEvent e;
    e.kind = kind;
    e.frame = frame;
    if (truth) e.truth_id = truth->track_id;
    if (hyp) e.track_id = hyp->track_id;
    e.range_m = bev_range_m(truth ? truth->box : hyp->box);
    return e;
}

/// Heading flips and the parked size spread of a matched hypothesis.
void track_shape(ClassState& s, std::int64_t frame, const TrackedObject& truth,
                 const TrackedObject& hyp, const TrackEvalOptions& options) {
    const auto& b = hyp.box;
    auto last = s.last_theta.find(hyp.track_id);
    if (last != s.last_theta.end() && std::abs(wrap_angle(b.theta - last->second)) > kPi / 2.0) {
        ++s.score.heading_flips;
        s.score.events.push_back(event(TrackEvent::Kind::kHeadingFlip, frame, &truth, &hyp));
    }
    s.last_theta[hyp.track_id] = b.theta;
    if (!truth.box.velocity || speed(truth.box) > options.moving_speed_mps) return;
    auto [it, fresh] = s.parked_size.try_emplace(
        hyp.track_id, std::array<double, 6>{b.W, b.W, b.H, b.H, b.L, b.L});
    auto& r = it->second;
    r = {std::min(r[0], b.W), std::max(r[1], b.W), std::min(r[2], b.H),
         std::max(r[3], b.H), std::min(r[4], b.L), std::max(r[5], b.L)};
    s.score.parked_size_spread_m =
        std::max({s.score.parked_size_spread_m, r[1] - r[0], r[3] - r[2], r[5] - r[4]});
}

/// One matched pair: counts, an ID switch or a fragmentation, the velocity error, the shape.
void score_match(ClassState& s, std::int64_t frame_index, const TrackedObject& gt,
                 const TrackedObject& hy, const TrackEvalOptions& options) {
    auto& all = s.score.bins[kAllBins];
    // Truth that is not owed is left out of the frame, as TrackEval's preprocessing removes
    // it: a track on it neither counts nor becomes the identity a later switch is from.
    if (!gt.owed) return;
    auto last = s.last_track.find(gt.track_id);
    const bool switched = last != s.last_track.end() && last->second != hy.track_id;
    const std::int64_t previous = switched ? last->second : -1;
    s.last_track[gt.track_id] = hy.track_id;
    const int bin = std::max(0, distance_bin(bev_range_m(gt.box)));
    auto& b = s.score.bins[bin];
    count(b, all, &TrackCounts::truth);
    count(b, all, &TrackCounts::hypotheses);
    count(b, all, &TrackCounts::matches);
    if (switched) {
        count(b, all, &TrackCounts::id_switches);
        s.score.events.push_back(event(TrackEvent::Kind::kIdSwitch, frame_index, &gt, &hy));
        s.score.events.back().previous_track = previous;
    }
    auto covered = s.covered.find(gt.track_id);
    if (covered != s.covered.end() && !covered->second) {
        count(b, all, &TrackCounts::fragmentations);
    }
    s.covered[gt.track_id] = true;
    if (gt.box.velocity && hy.box.velocity) {
        const double e = std::hypot(hy.box.velocity->vx_mps - gt.box.velocity->vx_mps,
                                    hy.box.velocity->vz_mps - gt.box.velocity->vz_mps);
        (speed(gt.box) > options.moving_speed_mps ? s.score.moving_velocity_errors_mps
                                                  : s.score.static_velocity_errors_mps)
            .push_back(e);
    }
    track_shape(s, frame_index, gt, hy, options);
}

/// The frame's identity overlaps (for IDF1) and its HOTA similarities.
void score_identities(ClassState& s, const std::vector<const TrackedObject*>& truth,
                      const std::vector<const TrackedObject*>& hyps,
                      const std::vector<std::pair<int, int>>& pairs,
                      const TrackEvalOptions& options) {
    // Identity overlaps: every owed truth / track pair within the distance, per frame.
    for (const auto* gt : truth) {
        if (!gt->owed) continue;
        ++s.truth_frames[gt->track_id];
        for (const auto* hy : hyps) {
            if (bev_distance(gt->box, hy->box) <= options.max_match_distance_m) {
                ++s.overlap[{gt->track_id, hy->track_id}];
            }
        }
    }
    HotaFrame frame;
    std::vector<const TrackedObject*> scored_truth, scored_hyps;
    for (const auto* gt : truth) {
        if (gt->owed) scored_truth.push_back(gt);
    }
    for (std::size_t h = 0; h < hyps.size(); ++h) {
        bool ignored = false;
        for (const auto& [t, hh] : pairs)
            ignored = ignored || (hh == static_cast<int>(h) && !truth[t]->owed);
        if (!ignored && distance_bin(bev_range_m(hyps[h]->box)) >= 0) {
            ++s.track_frames[hyps[h]->track_id];
            scored_hyps.push_back(hyps[h]);
        }
    }
    // HOTA's similarity: 1 at the same centre, 0 at the match distance (bird's eye).
    for (const auto* gt : scored_truth) {
        frame.truth.push_back(gt->track_id);
        for (const auto* hy : scored_hyps) {
            frame.similarity.push_back(
                std::max(0.0, 1.0 - bev_distance(gt->box, hy->box) / options.max_match_distance_m));
        }
    }
    for (const auto* hy : scored_hyps) frame.tracks.push_back(hy->track_id);
    s.hota_frames.push_back(std::move(frame));
}

void score_frame(ClassState& s, std::int64_t frame_index,
                 const std::vector<const TrackedObject*>& truth,
                 const std::vector<const TrackedObject*>& hyps, const TrackEvalOptions& options) {
    auto& all = s.score.bins[kAllBins];
    const auto pairs = match_frame(truth, hyps, s, options.max_match_distance_m);
    std::vector<char> truth_matched(truth.size(), 0), hyp_matched(hyps.size(), 0);
    for (const auto& [t, h] : pairs) {
        truth_matched[t] = hyp_matched[h] = 1;
        score_match(s, frame_index, *truth[t], *hyps[h], options);
    }
    for (std::size_t t = 0; t < truth.size(); ++t) {
        if (truth_matched[t] || !truth[t]->owed) continue;
        const int bin = std::max(0, distance_bin(bev_range_m(truth[t]->box)));
        count(s.score.bins[bin], all, &TrackCounts::truth);
        count(s.score.bins[bin], all, &TrackCounts::misses);
        s.score.events.push_back(event(TrackEvent::Kind::kMiss, frame_index, truth[t], nullptr));
        auto covered = s.covered.find(truth[t]->track_id);
        if (covered != s.covered.end()) covered->second = false;
    }
    for (std::size_t h = 0; h < hyps.size(); ++h) {
        if (hyp_matched[h]) continue;
        const int bin = distance_bin(bev_range_m(hyps[h]->box));
        if (bin < 0) continue;  // beyond the scored range
        count(s.score.bins[bin], all, &TrackCounts::hypotheses);
        count(s.score.bins[bin], all, &TrackCounts::false_positives);
        s.score.events.push_back(
            event(TrackEvent::Kind::kFalsePositive, frame_index, nullptr, hyps[h]));
    }
    score_identities(s, truth, hyps, pairs, options);
}

/// IDF1 = 2 IDTP / (truth + hypotheses) with the identity matching that maximises IDTP.
void identity_scores(ClassState& s) {
    std::vector<std::int64_t> truth_ids, track_ids;
    std::size_t truth_total = 0, track_total = 0;
    for (const auto& [id, n] : s.truth_frames) {
        truth_ids.push_back(id);
        truth_total += n;
    }
    for (const auto& [id, n] : s.track_frames) {
        track_ids.push_back(id);
        track_total += n;
    }
    tracking::CostMatrix m{
        static_cast<int>(truth_ids.size()), static_cast<int>(track_ids.size()), {}};
    for (auto t : truth_ids) {
        for (auto h : track_ids) {
            const auto it = s.overlap.find({t, h});
            m.cost.push_back(it == s.overlap.end() ? 0.0 : -static_cast<double>(it->second));
        }
    }
    std::size_t idtp = 0;
    for (const auto& match : tracking::assign(m, 1.0)) {
        idtp += static_cast<std::size_t>(-m.at(match.row, match.col));
    }
    s.score.id_true_positives = idtp;
    const std::size_t denominator = truth_total + track_total;
    s.score.idf1 = denominator == 0 ? 1.0 : 2.0 * static_cast<double>(idtp) / denominator;
}

}  // namespace

double TrackCounts::mota() const {
    if (truth == 0) return 1.0;
    return 1.0 - static_cast<double>(misses + false_positives + id_switches) / truth;
}

void TrackEvalOptions::validate() const {
    if (!(max_match_distance_m > 0.0 && std::isfinite(max_match_distance_m))) {
        throw std::invalid_argument("max_match_distance_m must be > 0");
    }
    if (!(max_range_m > 0.0 && max_range_m <= kDistanceBinEdges_m.back())) {
        throw std::invalid_argument("max_range_m must be in (0, 50]");
    }
    if (!(moving_speed_mps >= 0.0 && std::isfinite(moving_speed_mps))) {
        throw std::invalid_argument("moving_speed_mps must be >= 0");
    }
}

const ClassTrackScore& TrackEvaluation::of(const std::string& class_name) const {
    for (const auto& c : classes) {
        if (c.class_name == class_name) return c;
    }
    throw std::out_of_range("no tracking scores for class " + class_name);
}

TrackEvaluation evaluate_tracks(const std::vector<TrackedFrame>& frames,
                                const TrackEvalOptions& options) {
    options.validate();
    std::map<std::string, ClassState> states;
    for (const auto& c : options.classes) states[c].score.class_name = c;
    for (const TrackedFrame& frame : frames) {
        for (auto& [name, state] : states) {
            std::vector<TrackedObject> truth_copy;
            std::vector<const TrackedObject*> truth, hyps;
            for (const auto& t : frame.truth) {
                if (t.box.class_name != name) continue;
                truth_copy.push_back(t);
                if (bev_range_m(t.box) > options.max_range_m) truth_copy.back().owed = false;
            }
            for (const auto& t : truth_copy) truth.push_back(&t);
            for (const auto& h : frame.hypotheses) {
                if (h.box.class_name == name) hyps.push_back(&h);
            }
            score_frame(state, frame.index, truth, hyps, options);
        }
    }
    TrackEvaluation result;
    result.options = options;
    result.frames = frames.size();
    for (auto& [name, state] : states) {
        identity_scores(state);
        state.score.hota = hota(state.hota_frames);
        result.classes.push_back(std::move(state.score));
    }
    return result;
}

std::vector<TrackedObject> hypotheses_of(const scene_schema::EntityDocument& document) {
    std::vector<TrackedObject> out;
    for (const auto& e : document.entities) {
        if (e.track_id) out.push_back({*e.track_id, e, true});
    }
    return out;
}

std::vector<TrackedObject> truth_of(const scene_schema::EntityDocument& document,
                                    const std::vector<bool>& owed) {
    std::vector<TrackedObject> out;
    for (std::size_t i = 0; i < document.entities.size(); ++i) {
        const auto& e = document.entities[i];
        if (e.track_id) out.push_back({*e.track_id, e, i >= owed.size() || owed[i]});
    }
    return out;
}

std::string describe(const TrackEvent& event) {
    char line[160];
    const long long frame = event.frame, truth = event.truth_id, track = event.track_id;
    switch (event.kind) {
        case TrackEvent::Kind::kMiss:
            std::snprintf(line, sizeof line, "frame %lld miss: truth %lld at %.1f m", frame, truth,
                          event.range_m);
            break;
        case TrackEvent::Kind::kFalsePositive:
            std::snprintf(line, sizeof line, "frame %lld false positive: track %lld at %.1f m",
                          frame, track, event.range_m);
            break;
        case TrackEvent::Kind::kIdSwitch:
            std::snprintf(line, sizeof line,
                          "frame %lld id switch: truth %lld to track %lld (was %lld) at %.1f m",
                          frame, truth, track, static_cast<long long>(event.previous_track),
                          event.range_m);
            break;
        case TrackEvent::Kind::kHeadingFlip:
            std::snprintf(line, sizeof line,
                          "frame %lld heading flip: track %lld on truth %lld at %.1f m", frame,
                          track, truth, event.range_m);
            break;
    }
    return line;
}

bool TrackBars::any() const {
    return min_mota >= 0.0 || max_id_switches >= 0 || min_idf1 >= 0.0 ||
           max_median_moving_velocity_error_mps >= 0.0 ||
           max_median_still_velocity_error_mps >= 0.0 || max_heading_flips >= 0 ||
           max_parked_size_spread_m >= 0.0;
}

std::vector<std::string> check_track_bars(const TrackEvaluation& evaluation,
                                          const TrackBars& bars) {
    std::vector<std::string> missed;
    const ClassTrackScore* score = nullptr;
    for (const auto& c : evaluation.classes) {
        if (c.class_name == bars.class_name) score = &c;
    }
    if (!score) return {"no " + bars.class_name + " in the evaluation"};
    char line[160];
    const auto& all = score->bins[kAllBins];
    if (bars.min_mota >= 0.0 && all.mota() < bars.min_mota) {
        std::snprintf(line, sizeof line, "MOTA %.3f < %.3f (--min-mota)", all.mota(),
                      bars.min_mota);
        missed.push_back(line);
    }
    if (bars.max_id_switches >= 0 &&
        all.id_switches > static_cast<std::size_t>(bars.max_id_switches)) {
        std::snprintf(line, sizeof line, "ID switches %zu > %d (--max-id-switches)",
                      all.id_switches, bars.max_id_switches);
        missed.push_back(line);
    }
    if (bars.min_idf1 >= 0.0 && score->idf1 < bars.min_idf1) {
        std::snprintf(line, sizeof line, "IDF1 %.3f < %.3f (--min-idf1)", score->idf1,
                      bars.min_idf1);
        missed.push_back(line);
    }
    // A bar on the median velocity error of the moving or of the still objects.
    const auto velocity_bar = [&](const std::vector<double>& errors, double bar, const char* which,
                                  const char* flag) {
        const double v = median(errors);
        if (bar < 0.0 || v <= bar) return;
        std::snprintf(line, sizeof line, "median velocity error of %s objects %.3f m/s > %.3f (%s)",
                      which, v, bar, flag);
        missed.push_back(line);
    };
    velocity_bar(score->moving_velocity_errors_mps, bars.max_median_moving_velocity_error_mps,
                 "moving", "--max-velocity-error");
    velocity_bar(score->static_velocity_errors_mps, bars.max_median_still_velocity_error_mps,
                 "still", "--max-still-velocity-error");
    if (bars.max_heading_flips >= 0 &&
        score->heading_flips > static_cast<std::size_t>(bars.max_heading_flips)) {
        std::snprintf(line, sizeof line, "heading flips %zu > %d (--max-heading-flips)",
                      score->heading_flips, bars.max_heading_flips);
        missed.push_back(line);
    }
    if (bars.max_parked_size_spread_m >= 0.0 &&
        score->parked_size_spread_m > bars.max_parked_size_spread_m) {
        std::snprintf(line, sizeof line, "parked size spread %.3f m > %.3f (--max-size-spread)",
                      score->parked_size_spread_m, bars.max_parked_size_spread_m);
        missed.push_back(line);
    }
    return missed;
}

std::string format_track_report(const TrackEvaluation& evaluation) {
    std::ostringstream out;
    char line[200];
    out << "tracking over " << evaluation.frames << " frames (match within "
        << evaluation.options.max_match_distance_m << " m, bird's eye)\n";
    std::snprintf(line, sizeof line, "%-8s %-6s %6s %6s %6s %6s %5s %5s %7s\n", "class", "bin",
                  "truth", "TP", "FN", "FP", "IDSW", "Frag", "MOTA");
    out << line;
    for (const auto& c : evaluation.classes) {
        if (c.bins[kAllBins].truth == 0 && c.bins[kAllBins].hypotheses == 0) continue;
        for (std::size_t b = 0; b <= kAllBins; ++b) {
            const auto& k = c.bins[b];
            if (b < kAllBins && k.truth == 0 && k.hypotheses == 0) continue;
            std::snprintf(line, sizeof line, "%-8s %-6s %6zu %6zu %6zu %6zu %5zu %5zu %7.3f\n",
                          c.class_name.c_str(), distance_bin_name(static_cast<int>(b)).c_str(),
                          k.truth, k.matches, k.misses, k.false_positives, k.id_switches,
                          k.fragmentations, k.mota());
            out << line;
        }
    }
    for (const auto& c : evaluation.classes) {
        if (c.bins[kAllBins].truth == 0 && c.bins[kAllBins].hypotheses == 0) continue;
        std::snprintf(line, sizeof line,
                      "%s: IDF1 %.3f, HOTA %.3f (DetA %.3f, AssA %.3f, LocA %.3f), velocity "
                      "error median %.2f m/s moving (%zu), %.2f m/s still (%zu), heading flips "
                      "%zu, parked size spread %.3f m\n",
                      c.class_name.c_str(), c.idf1, c.hota.hota, c.hota.deta, c.hota.assa,
                      c.hota.loca, median(c.moving_velocity_errors_mps),
                      c.moving_velocity_errors_mps.size(), median(c.static_velocity_errors_mps),
                      c.static_velocity_errors_mps.size(), c.heading_flips, c.parked_size_spread_m);
        out << line;
    }
    return out.str();
}

}  // namespace cloud_analysis
