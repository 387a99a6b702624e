#include <catch2/catch.hpp>

#include <cmath>

#include "cloud_analysis/evaluation/hota.hpp"

using namespace cloud_analysis;

namespace {

/// A frame with one truth object and the given tracks, each at similarity `s`.
HotaFrame frame(std::vector<std::int64_t> tracks, double s = 1.0) {
    HotaFrame f;
    f.truth = {7};
    f.similarity.assign(tracks.size(), s);
    f.tracks = std::move(tracks);
    return f;
}

}  // namespace

TEST_CASE("HOTA is 1 for a perfect drive and for an empty one", "[hota]") {
    const HotaScore s = hota({frame({1}), frame({1}), frame({1})});
    CHECK(s.hota == Approx(1.0));
    CHECK(s.deta == Approx(1.0));
    CHECK(s.assa == Approx(1.0));
    CHECK(s.loca == Approx(1.0));
    CHECK(hota({}).hota == Approx(1.0));
}

TEST_CASE("HOTA halves detection and association for a truth found in one frame of two", "[hota]") {
    // TP 1, FN 1: DetA 1/2; the one match over truth 2 + track 1 - 1: AssA 1/2.
    const HotaScore s = hota({frame({1}), frame({})});
    CHECK(s.deta == Approx(0.5));
    CHECK(s.assa == Approx(0.5));
    CHECK(s.hota == Approx(0.5));
}

TEST_CASE("an identity switch half-way costs association, not detection", "[hota]") {
    // Track 1 for two frames, then track 2: each pair's A = 2 / (4 + 2 - 2) = 1/2.
    const HotaScore s = hota({frame({1}), frame({1}), frame({2}), frame({2})});
    CHECK(s.deta == Approx(1.0));
    CHECK(s.assa == Approx(0.5));
    CHECK(s.hota == Approx(std::sqrt(0.5)));
}

TEST_CASE("HOTA averages over the localisation thresholds", "[hota]") {
    // Similarity 0.5: matched for alpha 0.05..0.50 (10 of 19 thresholds), unmatched above.
    const HotaScore s = hota({frame({1}, 0.5), frame({1}, 0.5)});
    CHECK(s.hota == Approx(10.0 / 19.0));
    CHECK(s.loca == Approx((10 * 0.5 + 9 * 1.0) / 19.0));
}

TEST_CASE("the matching prefers the track aligned over the drive", "[hota]") {
    // Track 1 follows the truth in all three frames; track 2 shows up in the last one slightly
    // nearer. The alignment keeps track 1 (similarity alone would take track 2): no
    // association is lost at any threshold.
    HotaFrame last = frame({1, 2});
    last.similarity = {0.97, 0.99};
    const HotaScore s = hota({frame({1}), frame({1}), last});
    CHECK(s.assa == Approx(1.0).margin(1e-9));
    HotaFrame bad = frame({1});
    bad.similarity = {0.5, 0.5};
    CHECK_THROWS_AS(hota({bad}), std::invalid_argument);
}
