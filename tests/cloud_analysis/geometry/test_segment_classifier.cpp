// The stereo-only path's segment appearance and its vehicle classifier.
#include <cmath>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <memory>
#include <string>
#include <vector>

#include <unistd.h>

#include <catch2/catch.hpp>
#include <nlohmann/json.hpp>
#include <opencv2/ml.hpp>

#include "../kitti_rig.hpp"
#include "cloud_analysis/geometry/segment_classifier.hpp"
#include "synthetic_scene.hpp"

using cloud_analysis::ImageU8;
using namespace cloud_analysis::geometry;
using namespace test_scenes;
namespace fs = std::filesystem;

namespace {

const std::vector<Box> kCarAndWall =
    with_car_from_behind({{-12.0, -6.0, 14.0, 1.2}}, 10.0);  // a wall on the left

ImageU8 uniform_colour(const StereoCamera& c, std::uint8_t r, std::uint8_t g, std::uint8_t b) {
    ImageU8 left{c.width_px, c.height_px, 3, {}};
    for (int p = 0; p < c.width_px * c.height_px; ++p) {
        left.data.insert(left.data.end(), {r, g, b});
    }
    return left;
}

const Segment& segment_at(const SceneGeometry& g, const StereoCamera& c, std::pair<int, int> px) {
    const std::int32_t s =
        g.segment_of_pixel.at(static_cast<std::size_t>(px.second) * c.width_px + px.first);
    REQUIRE(s >= 0);
    return g.segments[static_cast<std::size_t>(s)];
}

/// A classifier's manifest beside its model file `model` (JSON members as given, defaults
/// otherwise: a vehicle classifier).
fs::path write_manifest(const fs::path& model, nlohmann::json doc = nlohmann::json::object()) {
    nlohmann::json full = {{"format", "stereoscene-vehicle-classifier"},
                           {"version", 1},
                           {"model", model.filename().string()},
                           {"features", std::vector<std::string>(kSegmentFeatureNames.begin(),
                                                                 kSegmentFeatureNames.end())},
                           {"vote_threshold", 0.5}};
    full.update(doc);
    const fs::path manifest = fs::path(model.string() + ".json");
    std::ofstream(manifest) << full.dump(1);
    return manifest;
}

/// Random trees over the segment features that call the target (a vehicle, or what `manifest`'s
/// format names) whatever has feature `name` above `threshold` (below it when `below`), trained
/// on features spread over [-2, 3] (the feature over [0, 20] for widths), written with their
/// manifest to files of the test's own; returns the manifest.
fs::path trees_calling_target(const std::string& name, double threshold, bool below,
                              const std::string& file_name,
                              const nlohmann::json& manifest = nlohmann::json::object()) {
    const int n = 400, f = static_cast<int>(kSegmentFeatureNames.size());
    cv::Mat x(n, f, CV_32F), y(n, 1, CV_32S);
    cv::RNG rng(7);
    rng.fill(x, cv::RNG::UNIFORM, -2.0, 3.0);
    int feature = 0;
    while (feature < f && name != kSegmentFeatureNames[static_cast<std::size_t>(feature)]) {
        ++feature;
    }
    REQUIRE(feature < f);
    if (name == "width_m") rng.fill(x.col(feature), cv::RNG::UNIFORM, 0.0, 20.0);
    for (int i = 0; i < n; ++i) {
        y.at<int>(i) = (x.at<float>(i, feature) > threshold) != below ? 1 : 0;
    }
    // Every split weighs every feature: the trees learn the rule whatever state OpenCV's
    // global generator (their bootstrap and feature draws) is left in by what ran before.
    auto trees = cv::ml::RTrees::create();
    trees->setActiveVarCount(f);
    trees->setMaxDepth(3);
    trees->setMinSampleCount(2);
    trees->setTermCriteria({cv::TermCriteria::MAX_ITER, 15, 0});
    trees->train(cv::ml::TrainData::create(x, cv::ml::ROW_SAMPLE, y));
    const fs::path file =
        fs::temp_directory_path() / ("stereoscene-" + std::to_string(::getpid()) + file_name);
    trees->save(file.string());
    return write_manifest(file, manifest);
}

fs::path trees_calling_above(double threshold, const std::string& name) {
    return trees_calling_target("fill", threshold, false, name);
}

void remove_trees(const fs::path& manifest) {
    fs::remove(manifest);
    fs::remove(manifest.parent_path() / manifest.stem());
}

}  // namespace

TEST_CASE("a segment's appearance: its colour's hue, the share of its box it fills, its surface",
          "[geometry][classifier]") {
    const StereoCamera cam = test_rigs::kitti_rig();
    const auto palette = cloud_analysis::load_palette("cityscapes");
    const auto disparity = render(cam, 1.65, kCarAndWall);
    const SceneGeometry g =
        derive_semantics(disparity, cam, uniform_colour(cam, 200, 100, 50), palette, {});
    const Segment& car = segment_at(g, cam, pixel_of(cam, 0.0, 0.8, 10.0));
    CHECK(car.label == "car");
    CHECK(car.rules_label == "car");
    CHECK(std::isnan(car.vehicle_votes));  // no classifier
    CHECK(car.chroma_r == Approx(201.0 / 353.0));
    CHECK(car.chroma_g == Approx(101.0 / 353.0));
    CHECK(car.chroma_b == Approx(51.0 / 353.0));
    CHECK(car.luma == Approx(350.0 / 3.0));
    CHECK(car.luma_cv == Approx(0.0).margin(1e-6));
    CHECK(car.grad == Approx(0.0).margin(1e-9));
    CHECK(car.fill > 0.5);
    CHECK(car.fill <= 1.0);
    // Back (10 m) and cabin (10.6 m): one step, rows apart; within each, one disparity.
    CHECK(car.rough_h < 0.05);
    CHECK(car.disparity_spread == Approx((cam.fx_px * cam.baseline_m) * (1 / 10.0 - 1 / 10.6) /
                                         (cam.fx_px * cam.baseline_m / 10.0))
                                      .margin(0.01));
    const std::vector<float> f = segment_features(car, cam.fx_px, cam.fy_px);
    REQUIRE(f.size() == kSegmentFeatureNames.size());
    CHECK(f[15] == Approx(car.chroma_r));
    CHECK(f[14] == Approx(car.pixels * car.depth_m * car.depth_m / (cam.fx_px * cam.fy_px)));
    CHECK(car.features == f);
    // Without a left image the colour is neutral.
    const SceneGeometry grey = derive_semantics(disparity, cam, ImageU8{}, palette, {});
    const Segment& plain = segment_at(grey, cam, pixel_of(cam, 0.0, 0.8, 10.0));
    CHECK(plain.chroma_r == Approx(1.0 / 3.0));
    CHECK(plain.luma == 0.0);
}

TEST_CASE("a surface whose disparity jumps between neighbours is rough", "[geometry][classifier]") {
    const StereoCamera cam = test_rigs::kitti_rig();
    const auto palette = cloud_analysis::load_palette("cityscapes");
    auto disparity = render(cam, 1.65, kCarAndWall);
    const float back = static_cast<float>(cam.fx_px * cam.baseline_m / 10.0);
    for (int v = 0; v < cam.height_px; ++v) {
        for (int u = 0; u < cam.width_px; ++u) {
            float& d = disparity.disparity_px[static_cast<std::size_t>(v) * cam.width_px + u];
            if (std::abs(d - back) < 0.01f) d += (u % 2) ? 0.4f : -0.4f;
        }
    }
    const SceneGeometry g = derive_semantics(disparity, cam, ImageU8{}, palette, {});
    const Segment& car = segment_at(g, cam, pixel_of(cam, 0.0, 0.5, 10.0));
    CHECK(car.rough_h > 0.5);  // every step along a row of the back
    CHECK(car.rough_v < 0.3);  // down a column the back stays one disparity
}

TEST_CASE("the vehicle classifier decides which segments are cars, the rules' call is kept",
          "[geometry][classifier]") {
    const StereoCamera cam = test_rigs::kitti_rig();
    const auto palette = cloud_analysis::load_palette("cityscapes");
    const auto disparity = render(cam, 1.65, kCarAndWall);
    const auto car_px = pixel_of(cam, 0.0, 0.8, 10.0), wall_px = pixel_of(cam, -9.0, 0.8, 14.0);
    GeometryOptions o;
    // Trees that call nothing a vehicle (no segment fills more than all of its box).
    const fs::path never = trees_calling_above(2.0, "-never.yml.gz");
    o.classifier = SegmentClassifier::load(never);
    SceneGeometry g = derive_semantics(disparity, cam, ImageU8{}, palette, o);
    CHECK(class_at(g, palette, car_px.first, car_px.second) == "static");
    const Segment& not_car = segment_at(g, cam, car_px);
    CHECK(not_car.label == "static");
    CHECK(not_car.rules_label == "car");
    CHECK(not_car.vehicle_votes < 0.5);
    CHECK(class_at(g, palette, wall_px.first, wall_px.second) == "wall");
    // Trees that call everything a vehicle.
    const fs::path always = trees_calling_above(-1.0, "-always.yml");
    o.classifier = SegmentClassifier::load(always);
    g = derive_semantics(disparity, cam, ImageU8{}, palette, o);
    CHECK(class_at(g, palette, car_px.first, car_px.second) == "car");
    CHECK(class_at(g, palette, wall_px.first, wall_px.second) == "car");
    CHECK(segment_at(g, cam, wall_px).rules_label == "wall");
    CHECK(segment_at(g, cam, wall_px).vehicle_votes > 0.5);
    for (const fs::path& m : {never, always}) remove_trees(m);
}

TEST_CASE("the person classifier decides which segments that are no car are persons",
          "[geometry][classifier]") {
    const StereoCamera cam = test_rigs::kitti_rig();
    const auto palette = cloud_analysis::load_palette("cityscapes");
    // A person-wide board (0.8 m wide, 1.45 m high) at 8 m beside the car and the wall.
    const auto disparity = render(
        cam, 1.65, with_car_from_behind({{-12.0, -6.0, 14.0, 1.2}, {2.0, 2.8, 8.0, 1.45}}, 10.0));
    const auto car_px = pixel_of(cam, 0.0, 0.8, 10.0), wall_px = pixel_of(cam, -9.0, 0.8, 14.0);
    const auto person_px = pixel_of(cam, 2.4, 0.7, 8.0);
    const nlohmann::json person_format = {{"format", "stereoscene-person-classifier"}};
    GeometryOptions o;
    SceneGeometry g = derive_semantics(disparity, cam, ImageU8{}, palette, o);
    REQUIRE(class_at(g, palette, person_px.first, person_px.second) == "person");
    CHECK(std::isnan(segment_at(g, cam, person_px).person_votes));
    // Trees that call nothing a person: the rules' person is static.
    const fs::path never =
        trees_calling_target("fill", 2.0, false, "-never-person.yml.gz", person_format);
    o.person_classifier = SegmentClassifier::load(never, SegmentTarget::person);
    g = derive_semantics(disparity, cam, ImageU8{}, palette, o);
    CHECK(class_at(g, palette, person_px.first, person_px.second) == "static");
    const Segment& not_person = segment_at(g, cam, person_px);
    CHECK(not_person.rules_label == "person");
    CHECK(not_person.person_votes < 0.5);
    CHECK(class_at(g, palette, wall_px.first, wall_px.second) == "wall");
    // Trees that call everything a person: every segment but the car (the car is asked of the
    // vehicle classifier, or left to the rules, never of the person trees).
    const fs::path always =
        trees_calling_target("fill", -1.0, false, "-always-person.yml", person_format);
    o.person_classifier = SegmentClassifier::load(always, SegmentTarget::person);
    g = derive_semantics(disparity, cam, ImageU8{}, palette, o);
    CHECK(class_at(g, palette, person_px.first, person_px.second) == "person");
    CHECK(class_at(g, palette, wall_px.first, wall_px.second) == "person");
    CHECK(segment_at(g, cam, wall_px).rules_label == "wall");
    CHECK(class_at(g, palette, car_px.first, car_px.second) == "car");
    CHECK(std::isnan(segment_at(g, cam, car_px).person_votes));
    // A person classifier is not a vehicle classifier, nor the other way round.
    CHECK_THROWS_WITH(SegmentClassifier::load(always),
                      Catch::EndsWith(": /format: must be \"stereoscene-vehicle-classifier\""));
    for (const fs::path& m : {never, always}) remove_trees(m);
}

TEST_CASE("a long car of the rules that the trees reject is judged again vehicle by vehicle",
          "[geometry][classifier]") {
    const StereoCamera cam = test_rigs::kitti_rig();
    const auto palette = cloud_analysis::load_palette("cityscapes");
    // A car, a van and a car parked side on, bumper to bumper, 12 m ahead: one surface 13.2 m
    // long, each one's flank up to its waist and its cabin 0.1 m behind it up to its roof.
    std::vector<Box> row;
    for (const auto& [x0, roof] : {std::pair{-6.6, 1.45}, {-2.2, 1.95}, {2.2, 1.5}}) {
        row.push_back({x0, x0 + 4.4, 12.0, 0.95});
        row.push_back({x0 + 0.9, x0 + 3.5, 12.1, roof});
    }
    const auto disparity = render(cam, 1.65, row);
    GeometryOptions o;
    // Trees that call a vehicle only what is at most 6 m long.
    const fs::path short_things = trees_calling_target("width_m", 6.0, true, "-short.yml.gz");
    o.classifier = SegmentClassifier::load(short_things);
    const SceneGeometry g = derive_semantics(disparity, cam, ImageU8{}, palette, o);
    for (const double x : {-4.4, 0.0, 4.4}) {
        const auto px = pixel_of(cam, x, 0.7, 12.0);
        CHECK(class_at(g, palette, px.first, px.second) == "car");
        const Segment& piece = segment_at(g, cam, px);
        CHECK(piece.rules_label == "car");
        CHECK(piece.width_m == Approx(4.4).margin(0.6));
    }
    // Cut into pieces of a bus's length, it stays one thing the trees reject.
    o.vehicle_piece_m = 12.0;
    const SceneGeometry whole = derive_semantics(disparity, cam, ImageU8{}, palette, o);
    const auto centre = pixel_of(cam, 0.0, 0.7, 12.0);
    CHECK(class_at(whole, palette, centre.first, centre.second) == "static");
    CHECK(segment_at(whole, cam, centre).width_m > 12.0);
    remove_trees(short_things);
}

TEST_CASE("a classifier that is missing, not a model or reads other features is refused",
          "[geometry][classifier]") {
    const fs::path dir =
        fs::temp_directory_path() / ("stereoscene-classifier-" + std::to_string(::getpid()));
    fs::create_directories(dir);
    const auto error = [](const fs::path& file) {
        try {
            SegmentClassifier::load(file);
        } catch (const std::runtime_error& e) {
            return std::string(e.what());
        }
        return std::string();
    };
    CHECK_THAT(error(dir / "none.json"), Catch::StartsWith((dir / "none.json").string() + ": "));
    std::ofstream(dir / "garbage.json") << "{ not json";
    CHECK_THAT(error(dir / "garbage.json"), Catch::Contains("garbage.json: not valid JSON"));
    // The manifest's rules, each named by its JSON pointer.
    const fs::path model = dir / "trees.yml";
    std::ofstream(model) << "%YAML:1.0\nhello: 1\n";
    CHECK(error(write_manifest(model, {{"format", "other"}})) ==
          (dir / "trees.yml.json").string() +
              ": /format: must be \"stereoscene-vehicle-classifier\"");
    CHECK_THAT(error(write_manifest(model, {{"version", 2}})),
               Catch::EndsWith(": /version: must be 1"));
    CHECK_THAT(error(write_manifest(model, {{"features", {"top_m"}}})),
               Catch::Contains(": /features: must be the segments' features in order (25"));
    CHECK_THAT(error(write_manifest(model, {{"vote_threshold", 1.0}})),
               Catch::EndsWith(": /vote_threshold: must be a number in (0, 1)"));
    CHECK_THAT(error(write_manifest(model, {{"model", "../trees.yml"}})),
               Catch::EndsWith(": /model: must name a file beside the manifest"));
    CHECK(error(write_manifest(model, {{"model", "gone.yml"}})) ==
          (dir / "gone.yml").string() + ": no such model file");
    // A model file that holds no trees, or trees over other features.
    CHECK(error(write_manifest(model)) ==
          model.string() + ": not a trained random trees classifier (cv::ml::RTrees)");
    std::ofstream(model) << "\x01\x02 not yaml {{{";
    CHECK(error(write_manifest(model)) ==
          model.string() + ": not a trained random trees classifier (cv::ml::RTrees)");
    cv::Mat x(20, 3, CV_32F), y(20, 1, CV_32S);
    cv::RNG(3).fill(x, cv::RNG::UNIFORM, 0.0, 1.0);
    for (int i = 0; i < 20; ++i) y.at<int>(i) = x.at<float>(i, 0) > 0.5f;
    auto trees = cv::ml::RTrees::create();
    trees->setMinSampleCount(2);
    trees->train(cv::ml::TrainData::create(x, cv::ml::ROW_SAMPLE, y));
    trees->save((dir / "three.yml").string());
    CHECK(error(write_manifest(dir / "three.yml")) ==
          (dir / "three.yml").string() + ": the model reads 3 features, the segments have 25");
    fs::remove_all(dir);
}

TEST_CASE("the project's classifiers load and read the segments' features",
          "[geometry][classifier]") {
    for (const SegmentTarget target : {SegmentTarget::vehicle, SegmentTarget::person}) {
        const auto classifier =
            SegmentClassifier::load(default_segment_classifier_path(target), target);
        CHECK(classifier->vote_threshold() > 0.0);
        CHECK(classifier->vote_threshold() < 1.0);
        const std::vector<float> none(kSegmentFeatureNames.size(), 0.0f);
        const double votes = classifier->votes(none);
        CHECK(votes >= 0.0);
        CHECK(votes <= 1.0);
    }
}
