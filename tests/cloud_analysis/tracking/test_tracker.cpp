#include <catch2/catch.hpp>

#include <algorithm>
#include <array>
#include <cmath>
#include <filesystem>
#include <functional>
#include <map>
#include <numeric>
#include <random>
#include <set>

#include "cloud_analysis/tracking/assignment.hpp"
#include "cloud_analysis/tracking/kalman.hpp"
#include "cloud_analysis/tracking/sequence.hpp"
#include "cloud_analysis/tracking/tracker.hpp"
#include "stereoscene/support/angles.hpp"

using stereoscene::support::radians;

using namespace cloud_analysis::tracking;
using scene_schema::Entity;
using scene_schema::EntityDocument;

namespace {

using stereoscene::support::kPi;

/// The cheapest total over every partial matching of admissible pairs that keeps as many
/// admissible pairs as possible (brute force over column permutations).
std::pair<int, double> brute_force(const CostMatrix& m, double gate) {
    std::vector<int> cols(std::max(m.rows, m.cols));
    std::iota(cols.begin(), cols.end(), 0);
    int best_count = -1;
    double best_cost = 0.0;
    do {
        int count = 0;
        double cost = 0.0;
        for (int r = 0; r < m.rows; ++r) {
            if (cols[r] < m.cols && m.at(r, cols[r]) <= gate) {
                ++count;
                cost += m.at(r, cols[r]);
            }
        }
        if (count > best_count || (count == best_count && cost < best_cost - 1e-12)) {
            best_count = count;
            best_cost = cost;
        }
    } while (std::next_permutation(cols.begin(), cols.end()));
    return {best_count, best_cost};
}

Entity car(double x, double z, double theta, double L = 4.2) {
    Entity e;
    e.id = "car";
    e.class_name = "car";
    e.class_id = 26;
    e.x = x;
    e.y = 0.9;
    e.z = z;
    e.theta = theta;
    e.W = 1.8;
    e.H = 1.5;
    e.L = L;
    return e;
}

EntityDocument frame_of(std::vector<Entity> entities) {
    EntityDocument doc;
    doc.frame.id = "f";
    for (std::size_t i = 0; i < entities.size(); ++i) entities[i].id += "-" + std::to_string(i);
    doc.entities = std::move(entities);
    return doc;
}

}  // namespace

TEST_CASE("assignment matches the brute-force optimum on random gated matrices", "[tracking]") {
    std::mt19937 rng(7);
    std::uniform_real_distribution<double> cost(0.0, 2.0);
    for (int trial = 0; trial < 300; ++trial) {
        CostMatrix m;
        m.rows = 1 + trial % 5;
        m.cols = 1 + (trial / 5) % 6;
        for (int i = 0; i < m.rows * m.cols; ++i) m.cost.push_back(cost(rng));
        const auto matches = assign(m, 1.0);
        std::set<int> rows, cols;
        double total = 0.0;
        for (const Match& match : matches) {
            CHECK(m.at(match.row, match.col) <= 1.0);
            rows.insert(match.row);
            cols.insert(match.col);
            total += m.at(match.row, match.col);
        }
        CHECK(rows.size() == matches.size());
        CHECK(cols.size() == matches.size());
        const auto [count, best] = brute_force(m, 1.0);
        INFO("trial " << trial);
        CHECK(static_cast<int>(matches.size()) == count);
        CHECK(total == Approx(best).margin(1e-9));
    }
}

TEST_CASE("assignment refuses a malformed matrix and handles empty sides", "[tracking]") {
    CHECK(assign(CostMatrix{0, 3, {}}, 1.0).empty());
    CHECK_THROWS_AS(assign(CostMatrix{2, 2, {1.0}}, 1.0), std::invalid_argument);
    CHECK_THROWS_AS(assign(CostMatrix{1, 1, {std::nan("")}}, 1.0), std::invalid_argument);
}

TEST_CASE("the Kalman filter recovers a constant velocity from noisy positions", "[tracking]") {
    std::mt19937 rng(3);
    std::normal_distribution<double> noise(0.0, 0.3);
    GroundKalman k(5.0, 20.0, KalmanOptions{});
    for (int i = 1; i <= 40; ++i) {
        const double t = 0.1 * i;
        k.predict(0.1);
        k.update(5.0 - 6.0 * t + noise(rng), 20.0 + 1.5 * t + noise(rng));
    }
    CHECK(k.vx_mps() == Approx(-6.0).margin(0.5));
    CHECK(k.vz_mps() == Approx(1.5).margin(0.5));
    CHECK(k.mahalanobis2(k.x_m(), k.z_m()) == Approx(0.0).margin(1e-12));
    CHECK_THROWS_AS(k.predict(-0.1), std::invalid_argument);
}

TEST_CASE("the measurement covariance is long along the viewing ray and narrow across it",
          "[tracking]") {
    KalmanOptions o;
    GroundKalman k(0.0, 10.0, o);
    // 30 m away, 30 degrees right of the camera's axis.
    const double x = 15.0, z = 25.980762113533160;
    const Eigen::Matrix2d R = k.measurement_covariance(x, z);
    const Eigen::Vector2d ray(0.5, z / 30.0), side(ray.y(), -ray.x());
    CHECK(ray.dot(R * ray) == Approx(std::pow(o.range_sigma_per_m2 * 900.0, 2)));
    CHECK(side.dot(R * side) == Approx(o.across_sigma_m * o.across_sigma_m));
    CHECK(ray.dot(R * side) == Approx(0.0).margin(1e-12));
    // Near the camera the floor holds along the ray.
    const Eigen::Matrix2d near = k.measurement_covariance(0.0, 5.0);
    CHECK(near(1, 1) == Approx(o.position_sigma_m * o.position_sigma_m));
    CHECK(near(0, 0) == Approx(o.across_sigma_m * o.across_sigma_m));
}

TEST_CASE("a parked car's track does not take the box of a car passing beside it", "[tracking]") {
    // A car parked 22 m ahead is seen for 2 s, then hidden for 0.5 s; a car coming the other
    // way in the next lane appears 1.7 m beside where it stands. Within the 2.5 m gate, but
    // far outside what the parked car's prediction allows across the viewing ray.
    const auto run = [](double gate_chi2) {
        TrackerOptions o;
        o.gate_chi2 = gate_chi2;
        Tracker tracker(o);
        std::mt19937 rng(5);
        std::normal_distribution<double> along(0.0, 0.4), across(0.0, 0.1);
        std::int64_t parked = -1;
        for (int i = 0; i < 20; ++i) {
            const auto out = tracker.update(
                frame_of({car(4.0 + across(rng), 22.5 + along(rng), -kPi / 2)}), 0.1 * i);
            parked = *out.entities[0].track_id;
        }
        for (int i = 20; i < 25; ++i) tracker.update(frame_of({}), 0.1 * i);
        const auto out = tracker.update(frame_of({car(2.3, 23.0, kPi / 2)}), 2.5);
        return out.entities[0].track_id && *out.entities[0].track_id == parked;
    };
    CHECK_FALSE(run(9.21));
    CHECK(run(0.0));  // distance alone: the parked car's track jumps onto the passing car
}

TEST_CASE("a confirmed track is matched before a tentative one nearer the box", "[tracking]") {
    TrackerOptions o;
    o.confirm_first_frames = false;
    Tracker tracker(o);
    std::int64_t parked = -1;
    for (int i = 0; i < 10; ++i) {
        parked =
            *tracker.update(frame_of({car(4.0, 22.0, -kPi / 2)}), 0.1 * i).entities[0].track_id;
    }
    // The parked car's box comes 0.6 m off; a stray box born last frame 0.3 m from it is
    // nearer, but a track seen once never takes the box of one followed for a second.
    tracker.update(frame_of({car(4.0, 22.0, -kPi / 2), car(4.3, 22.9, -kPi / 2)}), 1.0);
    const auto out = tracker.update(frame_of({car(4.4, 22.5, -kPi / 2)}), 1.1);
    REQUIRE(out.entities[0].track_id);
    CHECK(*out.entities[0].track_id == parked);
}

TEST_CASE("a crossing car and a parked car keep their ids, velocity and one size", "[tracking]") {
    std::mt19937 rng(11);
    std::normal_distribution<double> noise(0.0, 0.15);
    std::normal_distribution<double> size_noise(0.0, 0.1);
    std::bernoulli_distribution flip(0.3);
    Tracker tracker;
    std::map<std::string, std::set<std::int64_t>> ids;
    std::vector<double> parked_L;
    std::vector<double> moving_vx;
    double last_theta = 0.0;
    bool moving_known = false;
    for (int i = 0; i < 40; ++i) {
        const double t = 0.1 * i;
        // The moving car crosses left to right at 8 m/s, 2 m in front of the parked one; its
        // box heading comes flipped by pi in 30 % of the frames.
        const double theta = flip(rng) ? kPi : 0.0;
        auto moving = car(-16.0 + 8.0 * t + noise(rng), 18.0 + noise(rng), theta);
        auto parked = car(2.0 + noise(rng), 22.0 + noise(rng), -kPi / 2 + (flip(rng) ? kPi : 0.0),
                          4.2 + size_noise(rng));
        const auto out = tracker.update(frame_of({moving, parked}), t);
        REQUIRE(out.entities.size() == 2);
        for (const auto& e : out.entities) {
            REQUIRE(e.track_id);
            // Unknown at birth, so not written; known within a few frames.
            if (i == 0) CHECK_FALSE(e.velocity);
            if (i >= 8) REQUIRE(e.velocity);
        }
        ids["moving"].insert(*out.entities[0].track_id);
        ids["parked"].insert(*out.entities[1].track_id);
        if (i >= 3) parked_L.push_back(out.entities[1].L);
        if (i >= 10) moving_vx.push_back(out.entities[0].velocity->vx_mps);
        // Once its motion is known (a born-backwards track turns round once, when its velocity
        // is first known well enough to be reported), the heading changes smoothly: no flip
        // from a box measured the other way round.
        if (moving_known)
            CHECK(std::abs(std::remainder(out.entities[0].theta - last_theta, 2 * kPi)) < 0.3);
        moving_known = out.entities[0].velocity.has_value();
        last_theta = out.entities[0].theta;
        if (i >= 10) CHECK(std::cos(out.entities[0].theta) > 0.9);  // along +x, where it drives
    }
    CHECK(ids["moving"].size() == 1);
    CHECK(ids["parked"].size() == 1);
    CHECK(*ids["moving"].begin() != *ids["parked"].begin());
    const auto [lo, hi] = std::minmax_element(parked_L.begin(), parked_L.end());
    CHECK(*hi - *lo < 0.05);
    for (double vx : moving_vx) CHECK(vx == Approx(8.0).margin(1.0));
}

TEST_CASE(
    "with the camera's poses a parked car seen from a moving car is still, and a car "
    "driving alongside moves over the ground",
    "[tracking][odometry]") {
    std::mt19937 rng(5);
    std::normal_distribution<double> noise(0.0, 0.1);
    Tracker with_poses, without;
    std::vector<double> parked_speed, parked_speed_relative, moving_vz;
    for (int i = 0; i < 20; ++i) {
        const double t = 0.1 * i;
        // The camera drives at 15 m/s along its z and turns 0.5 degrees a frame; the parked car
        // stands at (4, 32) in the world, the other car drives at 10 m/s beside the camera's
        // start, along the world's z.
        const double yaw = radians(0.5) * i;
        const Eigen::Vector2d cam(0.0, 15.0 * t);  // the camera in the world (x, z)
        // World (x, z) -> this camera's (x, z): rotate by -yaw about y after the translation.
        const auto to_camera = [&](double wx, double wz) {
            const double dx = wx - cam.x(), dz = wz - cam.y();
            return Eigen::Vector2d(std::cos(yaw) * dx - std::sin(yaw) * dz,
                                   std::sin(yaw) * dx + std::cos(yaw) * dz);
        };
        const Eigen::Vector2d p = to_camera(4.0, 32.0), m = to_camera(-3.5, 5.0 + 10.0 * t);
        EntityDocument doc =
            frame_of({car(p.x() + noise(rng), p.y() + noise(rng), -kPi / 2 + yaw),
                      car(m.x() + noise(rng), m.y() + noise(rng), -kPi / 2 + yaw)});
        // T_world_camera: R_y(yaw) and the camera's position.
        doc.frame.pose =
            std::array<double, 12>{std::cos(yaw),  0.0, std::sin(yaw), cam.x(), 0.0, 1.0, 0.0, 0.0,
                                   -std::sin(yaw), 0.0, std::cos(yaw), cam.y()};
        const auto out = with_poses.update(doc, t);
        doc.frame.pose.reset();
        const auto relative = without.update(doc, t);
        if (i < 8) continue;
        REQUIRE(out.entities[0].velocity);
        REQUIRE(relative.entities[0].velocity);
        parked_speed.push_back(
            std::hypot(out.entities[0].velocity->vx_mps, out.entities[0].velocity->vz_mps));
        parked_speed_relative.push_back(std::hypot(relative.entities[0].velocity->vx_mps,
                                                   relative.entities[0].velocity->vz_mps));
        // Over the ground, in this camera's axes: 10 m/s along the world's z, turned by -yaw.
        moving_vz.push_back(
            std::hypot(out.entities[1].velocity->vx_mps, out.entities[1].velocity->vz_mps));
        CHECK(out.entities[0].x == Approx(p.x()).margin(0.3));  // still the camera's frame
        CHECK(out.entities[0].z == Approx(p.y()).margin(0.3));
    }
    for (double v : parked_speed) CHECK(v < 0.5);
    for (double v : parked_speed_relative) CHECK(v > 10.0);  // the camera's own motion
    for (double v : moving_vz) CHECK(v == Approx(10.0).margin(1.0));
}

TEST_CASE("a track is reported after min_hits and dies after max_misses", "[tracking]") {
    TrackerOptions options;
    options.min_hits = 3;
    options.max_misses = 2;
    Tracker tracker(options);
    auto report = [&](int i, bool present) {
        std::vector<Entity> seen{car(0.0, 10.0, 0.0)};
        if (present) seen.push_back(car(5.0, 30.0, 0.0));
        const auto out = tracker.update(frame_of(seen), 0.1 * i);
        return present ? out.entities[1].track_id : std::optional<std::int64_t>{};
    };
    for (int i = 0; i < 5; ++i) report(i, false);  // past the start-up frames
    CHECK_FALSE(report(5, true));
    CHECK_FALSE(report(6, true));
    const auto id = report(7, true);
    REQUIRE(id);
    report(8, false);  // one miss: the track survives
    CHECK(report(9, true) == id);
    report(10, false);
    report(11, false);  // two misses: it dies
    CHECK_FALSE(report(12, true));
    CHECK(tracker.tracks().size() == 2);
}

TEST_CASE("time going back or a long gap restarts the tracker with new ids", "[tracking]") {
    Tracker tracker;
    TrackerFrameStats stats;
    const auto first = tracker.update(frame_of({car(0.0, 10.0, 0.0)}), 1.0, &stats);
    CHECK_FALSE(stats.restarted);
    CHECK(tracker.update(frame_of({car(0.0, 10.0, 0.0)}), 1.1, &stats).entities[0].track_id ==
          first.entities[0].track_id);
    const auto back = tracker.update(frame_of({car(0.0, 10.0, 0.0)}), 0.5, &stats);
    CHECK(stats.restarted);
    CHECK(back.entities[0].track_id != first.entities[0].track_id);
    const auto gap = tracker.update(frame_of({car(0.0, 10.0, 0.0)}), 5.0, &stats);
    CHECK(stats.restarted);
    CHECK(gap.entities[0].track_id != back.entities[0].track_id);
    CHECK_FALSE(gap.entities[0].velocity);  // a new track: its velocity is not known yet
}

TEST_CASE("untracked classes pass through and classes never share a track", "[tracking]") {
    Tracker tracker;
    Entity road = car(0.0, 20.0, 0.0, 40.0);
    road.class_name = "road";
    road.class_id = 7;
    Entity person = car(0.5, 10.0, 0.0);
    person.class_name = "person";
    const auto a = tracker.update(frame_of({road, car(0.0, 10.0, 0.0)}), 0.0);
    const auto b = tracker.update(frame_of({road, person}), 0.1);
    CHECK_FALSE(a.entities[0].track_id);
    CHECK(a.entities[0].L == 40.0);
    REQUIRE(b.entities[1].track_id);
    CHECK(*b.entities[1].track_id != *a.entities[1].track_id);
}

TEST_CASE("tracker options name the bad field", "[tracking]") {
    TrackerOptions o;
    o.min_hits = 0;
    CHECK_THROWS_WITH(o.validate(), "min_hits must be >= 1");
    o = TrackerOptions{};
    o.gate_m["car"] = -1.0;
    CHECK_THROWS_WITH(o.validate(), "gate_m[car] must be > 0");
    o = TrackerOptions{};
    o.kalman.position_sigma_m = 0.0;
    CHECK_THROWS_WITH(o.validate(), "position_sigma_m must be > 0");
    o = TrackerOptions{};
    o.kalman.across_sigma_m = -1.0;
    CHECK_THROWS_WITH(o.validate(), "across_sigma_m must be > 0");
    o = TrackerOptions{};
    o.gate_chi2 = -1.0;
    CHECK_THROWS_WITH(o.validate(), "gate_chi2 must be >= 0");
    o = TrackerOptions{};
    o.max_velocity_sigma_mps = 0.0;
    CHECK_THROWS_WITH(o.validate(), "max_velocity_sigma_mps must be > 0");
    CHECK_THROWS_AS(track_sequence({EntityDocument{}}, {}, TrackerOptions{}),
                    std::invalid_argument);
}

TEST_CASE("a missed confirmed track coasts at its prediction for coast_frames frames",
          "[tracking]") {
    TrackerOptions options;
    options.coast_frames = 2;
    Tracker tracker(options);
    // A car driving forward at 5 m/s, confirmed, then lost by the detector for three frames.
    for (int i = 0; i < 6; ++i) {
        Entity e = car(1.0, 10.0 + 0.5 * i, kPi / 2);
        e.confidence = 0.8;
        tracker.update(frame_of({e}), 0.1 * i);
    }
    const auto missed = [&](int i) { return tracker.update(frame_of({}), 0.1 * i); };
    const auto first = missed(6);
    REQUIRE(first.entities.size() == 1);
    const Entity& p = first.entities[0];
    CHECK(p.method == std::optional<std::string>("track prediction"));
    CHECK(p.id.rfind("track-", 0) == 0);
    CHECK(p.track_id);
    CHECK(p.class_name == "car");
    CHECK(p.class_id == 26);
    CHECK(p.point_count == 0);
    CHECK(p.confidence == Approx(0.4));
    CHECK(p.z == Approx(13.0).margin(0.15));  // predicted on, not where it was last seen
    const auto second = missed(7);
    REQUIRE(second.entities.size() == 1);
    CHECK(second.entities[0].confidence == Approx(0.2));
    CHECK(second.entities[0].track_id == p.track_id);
    CHECK(missed(8).entities.empty());    // a third miss: no longer reported
    CHECK(tracker.tracks().size() == 1);  // still alive until max_misses
}

TEST_CASE("a track lost right after its confirmation does not coast", "[tracking]") {
    TrackerOptions options;
    options.confirm_first_frames = false;
    options.coast_min_hits = 6;
    Tracker tracker(options);
    // Three stray boxes in a row confirm a track, then nothing: no prediction is reported.
    for (int i = 0; i < 3; ++i) {
        CHECK(tracker.update(frame_of({car(4.0, 17.3, -kPi / 2)}), 0.1 * i).entities.size() == 1);
    }
    CHECK(tracker.update(frame_of({}), 0.3).entities.empty());
    options.coast_min_hits = 0;  // every confirmed track coasts
    Tracker every(options);
    for (int i = 0; i < 3; ++i) every.update(frame_of({car(4.0, 17.3, -kPi / 2)}), 0.1 * i);
    CHECK(every.update(frame_of({}), 0.3).entities.size() == 1);
    options.coast_min_hits = -1;
    CHECK_THROWS_WITH(options.validate(), "coast_min_hits must be >= 0");
}

TEST_CASE("a parked car seen in part through passing traffic is reported for support_frames",
          "[tracking]") {
    TrackerOptions options;
    options.support_frames = 10;
    options.coast_frames = 2;
    // A parked car along the street (heading +z) tracked for a second, then only a sliver of it
    // shows past a passing car, which the stereo-only rules call a person: 0.6 m across and
    // 1.5 m along from its centre, on its footprint.
    const auto sliver = [](double x, double z) {
        Entity e = car(x, z, 0.0, 0.5);
        e.id = "person";
        e.class_name = "person";
        e.class_id = 24;
        e.W = 0.5;
        return e;
    };
    const auto reported_cars = [](const EntityDocument& doc) {
        int n = 0;
        for (const Entity& e : doc.entities) n += e.class_name == "car" && e.track_id ? 1 : 0;
        return n;
    };
    const auto parked = [&](double dx, double dz) {
        Tracker tracker(options);
        int i = 0;
        for (; i < 10; ++i) tracker.update(frame_of({car(-4.0, 22.0, kPi / 2)}), 0.1 * i);
        std::vector<int> seen;
        for (; i < 24; ++i) {
            seen.push_back(
                reported_cars(tracker.update(frame_of({sliver(-4.0 + dx, 22.0 + dz)}), 0.1 * i)));
        }
        return seen;
    };
    // On its footprint: ten frames at its prediction, then the two frames any miss coasts.
    std::vector<int> expected(14, 0);
    std::fill(expected.begin(), expected.begin() + 12, 1);
    CHECK(parked(-0.6, -1.5) == expected);
    // 2.5 m beside it (a person on the sidewalk): a miss like any other, two frames of coasting.
    std::fill(expected.begin() + 2, expected.end(), 0);
    CHECK(parked(-2.5, 0.0) == expected);
    // A car driving on at 5 m/s is no still track: the same two frames.
    Tracker moving(options);
    int i = 0;
    for (; i < 10; ++i) moving.update(frame_of({car(1.0, 10.0 + 0.5 * i, kPi / 2)}), 0.1 * i);
    std::vector<int> seen;
    for (; i < 24; ++i) {
        seen.push_back(reported_cars(moving.update(frame_of({sliver(1.3, 15.0)}), 0.1 * i)));
    }
    CHECK(seen == expected);
    options.support_frames = -1;
    CHECK_THROWS_WITH(options.validate(), "support_frames must be in 0..1000");
}

TEST_CASE("a confirmed track's size is fixed by default", "[tracking]") {
    Tracker tracker;
    std::vector<EntityDocument> out;
    for (int i = 0; i < 12; ++i) {
        // A parked car first seen truncated (3 m long), then whole (4.5 m).
        out.push_back(tracker.update(frame_of({car(2.0, 15.0, 0.0, i < 4 ? 3.0 : 4.5)}), 0.1 * i));
    }
    const double L = out[3].entities[0].L;
    for (std::size_t i = 3; i < out.size(); ++i) CHECK(out[i].entities[0].L == Approx(L));
}

TEST_CASE(
    "a parked car's jittering box does not turn its heading round before its velocity is known",
    "[tracking]") {
    // The second box lands 0.4 m further on: 4 m/s from two boxes at 10 fps, over the 2 m/s at
    // which motion decides the heading, but with a velocity too uncertain to be reported.
    Tracker tracker;
    const std::vector<double> z = {20.0, 19.6, 19.9, 20.1, 19.8, 20.0, 20.1, 19.9};
    for (std::size_t i = 0; i < z.size(); ++i) {
        const auto out = tracker.update(frame_of({car(3.0, z[i], -kPi / 2)}), 0.1 * i);
        REQUIRE(out.entities.size() == 1);
        const auto& e = out.entities[0];
        CHECK(std::abs(std::remainder(e.theta + kPi / 2, 2 * kPi)) < 0.3);
        if (i == 1) CHECK_FALSE(e.velocity);
    }
}

TEST_CASE("the tracker says which tracks the direction of motion turned round", "[tracking]") {
    // A car driving +x at 6 m/s whose boxes all face -x (theta pi): reported backwards from the
    // first frames, turned round once its velocity is known.
    Tracker tracker;
    std::int64_t turned_id = -1;
    int turned_at = -1;
    for (int i = 0; i < 10; ++i) {
        TrackerFrameStats stats;
        const auto out =
            tracker.update(frame_of({car(-10.0 + 0.6 * i, 15.0, kPi)}), 0.1 * i, &stats);
        REQUIRE(out.entities.size() == 1);
        if (!stats.turned.empty()) {
            CHECK(turned_at == -1);  // once
            turned_at = i;
            turned_id = stats.turned.front();
            CHECK(turned_id == *out.entities[0].track_id);
        }
    }
    CHECK(turned_at > 0);
    CHECK(turned_id >= 0);
}

namespace {

std::filesystem::path fresh_dir(const std::string& name) {
    const auto dir = std::filesystem::temp_directory_path() / ("cloud_analysis_tracking_" + name);
    std::filesystem::remove_all(dir);
    std::filesystem::create_directories(dir);
    return dir;
}

/// Heading changes over 90 degrees between consecutive frames of one track in a tracked folder.
int heading_flips(const std::filesystem::path& dir, int frames) {
    std::map<std::int64_t, double> last;
    int flips = 0;
    for (int i = 0; i < frames; ++i) {
        const auto doc = scene_schema::read_file(dir / ("f" + std::to_string(i) + ".json"));
        for (const auto& e : doc.entities) {
            if (!e.track_id) continue;
            const auto it = last.find(*e.track_id);
            if (it != last.end() &&
                std::abs(std::remainder(e.theta - it->second, 2 * kPi)) > kPi / 2)
                ++flips;
            last[*e.track_id] = e.theta;
        }
    }
    return flips;
}

/// A drive of `frames` entity files f<i>.json in `dir`, 0.1 s apart, frame i holding
/// entities_of(i), and its sequence index (written as dir/sequence.json).
scene_schema::SequenceIndex write_drive(
    const std::filesystem::path& dir, const std::string& id, int frames,
    const std::function<std::vector<Entity>(int)>& entities_of) {
    scene_schema::SequenceIndex index;
    index.id = id;
    for (int i = 0; i < frames; ++i) {
        auto doc = frame_of(entities_of(i));
        doc.frame.id = std::to_string(i);
        const std::string file = "f" + std::to_string(i) + ".json";
        scene_schema::write_file(doc, dir / file);
        index.frames.push_back({i, file, 0.1 * i, {}});
    }
    scene_schema::write_sequence_file(index, dir / "sequence.json");
    return index;
}

}  // namespace

TEST_CASE("track_files with a lag turns a backwards-born track round in the frames it holds",
          "[tracking]") {
    const auto in = fresh_dir("lag_in");
    const int frames = 12;
    const auto index = write_drive(in, "lag", frames, [](int i) {
        return std::vector<Entity>{car(-10.0 + 0.6 * i, 15.0, kPi), car(4.0, 20.0, kPi / 2)};
    });
    const auto quiet = [](const std::string&) {};

    SequenceTrackOptions options;
    options.lag_frames = 0;
    const auto at_once = fresh_dir("lag_0");
    track_files(index, in / "sequence.json", at_once, options, quiet);
    CHECK(heading_flips(at_once, frames) == 1);  // the moving car turns round once

    options.lag_frames = 5;
    const auto lagged = fresh_dir("lag_5");
    const auto report = track_files(index, in / "sequence.json", lagged, options, quiet);
    CHECK(report.tracked == static_cast<std::size_t>(frames));
    CHECK(heading_flips(lagged, frames) == 0);
    // Every frame is written and indexed, in order, and the moving car faces +x throughout.
    const auto written = scene_schema::read_sequence_file(lagged / "sequence.json");
    REQUIRE(written.frames.size() == static_cast<std::size_t>(frames));
    for (int i = 0; i < frames; ++i) {
        CHECK(written.frames[i].file == "f" + std::to_string(i) + ".json");
        const auto doc = scene_schema::read_file(lagged / written.frames[i].file);
        for (const auto& e : doc.entities) {
            if (e.track_id && std::abs(e.z - 15.0) < 1.0)
                CHECK(std::abs(std::remainder(e.theta, 2 * kPi)) < 0.5);
        }
    }
}

TEST_CASE("a track confirmed after min_hits says which entities it was made of", "[tracking]") {
    TrackerOptions options;
    options.min_hits = 3;
    Tracker tracker(options);
    for (int i = 0; i < 5; ++i) tracker.update(frame_of({car(0.0, 10.0, 0.0)}), 0.1 * i);
    std::vector<std::string> ids;
    for (int i = 5; i < 8; ++i) {
        TrackerFrameStats stats;
        auto doc = frame_of({car(0.0, 10.0, 0.0), car(5.0, 30.0, kPi / 2)});
        doc.entities[1].id = "car-in-" + std::to_string(i);
        const auto out = tracker.update(doc, 0.1 * i, &stats);
        if (i < 7) {
            CHECK(stats.confirmed.empty());
            continue;
        }
        REQUIRE(stats.confirmed.size() == 1);
        CHECK(stats.confirmed[0].id == *out.entities[1].track_id);
        ids = stats.confirmed[0].earlier_entity_ids;
        CHECK(stats.confirmed[0].reported.L == Approx(out.entities[1].L));
    }
    CHECK(ids == std::vector<std::string>{"car-in-5", "car-in-6"});
}

TEST_CASE("track_files with a lag reports a track from its first detection", "[tracking]") {
    const auto in = fresh_dir("first_in");
    const int frames = 12;
    // A parked car from the first frame (confirmed at once), another from frame 6.
    const auto index = write_drive(in, "first", frames, [](int i) {
        std::vector<Entity> seen{car(0.0, 10.0, 0.0)};
        if (i >= 6) seen.push_back(car(5.0, 30.0, kPi / 2, 3.9 + 0.1 * (i % 3)));
        return seen;
    });
    const auto quiet = [](const std::string&) {};
    // The ids of the later car's entities, frame by frame (none where it is not reported).
    const auto later_ids = [&](const std::filesystem::path& dir) {
        std::vector<std::optional<std::int64_t>> ids;
        std::set<double> lengths;
        for (int i = 6; i < frames; ++i) {
            const auto doc = scene_schema::read_file(dir / ("f" + std::to_string(i) + ".json"));
            ids.push_back(doc.entities.at(1).track_id);
            if (doc.entities[1].track_id) lengths.insert(doc.entities[1].L);
        }
        return std::make_pair(ids, lengths);
    };
    SequenceTrackOptions options;
    options.tracker.min_hits = 3;
    options.lag_frames = 0;
    const auto at_once = fresh_dir("first_0");
    track_files(index, in / "sequence.json", at_once, options, quiet);
    const auto [live, live_lengths] = later_ids(at_once);
    CHECK_FALSE(live[0]);
    CHECK_FALSE(live[1]);
    REQUIRE(live[2]);

    options.lag_frames = 5;
    const auto lagged = fresh_dir("first_5");
    track_files(index, in / "sequence.json", lagged, options, quiet);
    const auto [held, held_lengths] = later_ids(lagged);
    for (const auto& id : held) CHECK(id == live[2]);
    CHECK(held_lengths.size() == 1);  // one held size, the earlier frames' too
}

TEST_CASE("sequence track options refuse a negative lag", "[tracking]") {
    SequenceTrackOptions options;
    options.lag_frames = -1;
    CHECK_THROWS_WITH(options.validate(), Catch::Contains("lag_frames"));
}
