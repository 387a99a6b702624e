#include <algorithm>
#include <cmath>
#include <limits>
#include <numeric>
#include <optional>
#include <vector>

#include <catch2/catch.hpp>

#include "../kitti_rig.hpp"
#include "cloud_analysis/cloud/semantic.hpp"
#include "cloud_analysis/entities/extract.hpp"
#include "cloud_analysis/entities/row_split.hpp"
#include "cloud_analysis/entities/suppression.hpp"
#include "stereoscene/support/angles.hpp"

using namespace cloud_analysis;

namespace {

using stereoscene::support::kPi;

/// A tiny palette: road, sky, car (thing).
Palette test_palette() {
    Palette p;
    p.name = "test";
    p.classes = {{"road", 7, false, {128, 64, 128}},
                 {"sky", 23, false, {70, 130, 180}},
                 {"car", 26, true, {0, 0, 142}}};
    return p;
}

void add_point(LabeledCloud& cloud, const Eigen::Vector3f& p, std::uint16_t cls) {
    cloud.xyz_m.push_back(p);
    cloud.colour.push_back({0, 0, 0});
    cloud.class_index.push_back(cls);
    cloud.pixel.push_back(static_cast<std::uint32_t>(cloud.pixel.size()));
}

/// Rear and right side of a car heading along +z, standing on y = 1.65.
void add_car(LabeledCloud& cloud, float x, float z) {
    for (float y = 1.65f - 1.5f; y <= 1.65f; y += 0.05f) {
        for (float a = -0.9f; a <= 0.9f; a += 0.05f) add_point(cloud, {x + a, y, z - 2.1f}, 2);
        for (float b = -2.1f; b <= 2.1f; b += 0.05f) {
            add_point(cloud, {x + (x < 0 ? 0.9f : -0.9f), y, z + b}, 2);
        }
    }
}

/// Road y = 1.65 from z 3 to 40, x -6..6.
void add_road(LabeledCloud& cloud) {
    for (float x = -6.0f; x <= 6.0f; x += 0.25f) {
        for (float z = 3.0f; z <= 40.0f; z += 0.25f) add_point(cloud, {x, 1.65f, z}, 0);
    }
}

/// The right sides (x = -1.1, 1.5 m high) of 4.2 m cars parked along z from each start.
void add_row_sides(LabeledCloud& cloud, const std::vector<float>& starts) {
    for (float start : starts) {
        for (float y = 0.15f; y <= 1.65f; y += 0.05f) {
            for (float z = start; z <= start + 4.2f; z += 0.05f) add_point(cloud, {-1.1f, y, z}, 2);
        }
    }
}

/// Road y = 1.65 from z 3 to 40, x -6..6, and a sky patch far away.
LabeledCloud test_scene() {
    LabeledCloud cloud;
    add_road(cloud);
    for (float x = -5.0f; x <= 5.0f; x += 0.5f) add_point(cloud, {x, -10.0f, 50.0f}, 1);
    add_car(cloud, -3.5f, 12.0f);
    add_car(cloud, 3.5f, 20.0f);
    return cloud;
}

ExtractOptions options_with_bundled_config(const std::string& method) {
    ExtractOptions o;
    o.method = method;
    o.classes = load_class_config(std::string(STEREOSCENE_SOURCE_DIR) +
                                  "/assets/classes/entity_config.json");
    return o;
}

/// The car entities of a cloud with these options (default: the bundled class settings).
std::vector<scene_schema::Entity> cars_of(
    const LabeledCloud& cloud,
    const ExtractOptions& options = options_with_bundled_config("instances")) {
    std::vector<scene_schema::Entity> cars;
    for (const auto& e :
         extract_entities(cloud, test_palette(), StereoCamera{}, options).entities) {
        if (e.class_name == "car") cars.push_back(e);
    }
    return cars;
}

}  // namespace

TEST_CASE("the bundled class config loads with the documented car prior", "[entities]") {
    const ClassConfig c = load_class_config(std::string(STEREOSCENE_SOURCE_DIR) +
                                            "/assets/classes/entity_config.json");
    const ClassSettings car = c.find("car");
    CHECK(car.thing);
    CHECK(car.prior_L_m == 4.2);
    CHECK(car.prior_W_m == 1.8);
    CHECK(car.prior_H_m == 1.5);
    // Cars link across the viewing ray within 0.4 m at any depth; other classes isotropically.
    REQUIRE(car.cluster_cross_growth.has_value());
    CHECK(*car.cluster_cross_growth == 0.0);
    CHECK_FALSE(c.find("vegetation").cluster_cross_growth.has_value());
    CHECK_FALSE(c.find("sky").entity);
    CHECK(c.find("some class nobody listed").name == "some class nobody listed");
    CHECK(default_class_config_path().filename() == "entity_config.json");
}

TEST_CASE("voxels double with depth where the clustering distance doubles, up to voxel_max_m",
          "[entities]") {
    const ClassConfig c = load_class_config(std::string(STEREOSCENE_SOURCE_DIR) +
                                            "/assets/classes/entity_config.json");
    // Stuff: 1 m at 10 m growing linearly, capped at 2 m: 0.4 m voxels, 0.8 m from 20 m.
    const std::vector<double> stuff = c.find("vegetation").voxel_doubling_depths();
    REQUIRE(stuff.size() == 1);
    CHECK(stuff[0] == Approx(20.0));
    // Things keep their fine voxels (voxel_max_m 0).
    CHECK(c.find("car").voxel_doubling_depths().empty());
    // Cars' distance (0.4 m at 10 m growing with z^2, capped at 1.5 m) with a larger voxel_max_m:
    // doubled (0.8 m) at 10 * sqrt(2) m; 1.6 m is over the cap.
    ClassSettings car = c.find("car");
    car.voxel_max_m = 0.8;
    const std::vector<double> car_depths = car.voxel_doubling_depths();
    REQUIRE(car_depths.size() == 1);
    CHECK(car_depths[0] == Approx(10.0 * std::sqrt(2.0)));
    ClassSettings s;
    s.voxel_m = 0.1;
    s.cluster_distance_m = 0.5;
    s.cluster_growth = 1.0;
    s.cluster_distance_max_m = 100.0;
    CHECK(s.voxel_doubling_depths().empty());  // voxel_max_m 0: the edge stays voxel_m
    s.voxel_max_m = 0.4;
    CHECK(s.voxel_doubling_depths() == std::vector<double>{20.0, 40.0});
    s.cluster_growth = 0.0;
    CHECK(s.voxel_doubling_depths().empty());  // a constant distance never doubles
    CHECK_THROWS_WITH(
        parse_class_config(R"({"classes": [{"name": "car", "voxel_m": 0.4, "voxel_max_m": 0.2}]})",
                           "x"),
        Catch::Contains("voxel_max_m"));
}

TEST_CASE("a malformed class config names the bad member", "[entities]") {
    CHECK_THROWS_WITH(parse_class_config(R"({"classes": [{"name": "car", "min_points": 0}]})", "x"),
                      Catch::Contains("min_points"));
    CHECK_THROWS_WITH(parse_class_config(R"({"classes": [{"name": "car", "prior_L": 4}]})", "x"),
                      Catch::Contains("/classes/0/prior_L: unknown member"));
    CHECK_THROWS_WITH(parse_class_config(R"({"classes": [{"thing": true}]})", "x"),
                      Catch::Contains("/classes/0/name"));
    CHECK_THROWS_WITH(
        parse_class_config(R"({"classes": [{"name": "car", "cluster_cross_growth": 3}]})", "x"),
        Catch::Contains("cluster_cross_growth"));
    CHECK_THROWS_WITH(
        parse_class_config(R"({"classes": [{"name": "car", "cluster_cross_growth": "0"}]})", "x"),
        Catch::Contains("/classes/0/cluster_cross_growth: must be a number"));
    CHECK_THROWS_WITH(parse_class_config(R"({"classes": [{"name": "car", "cluster_distance_m": 0.4,
                                             "cluster_cross_distance_m": 0.5}]})",
                                         "x"),
                      Catch::Contains("cluster_cross_distance_m"));
    const auto parsed = parse_class_config(
        R"({"classes": [{"name": "car", "cluster_distance_m": 0.4, "cluster_cross_distance_m": 0.3}]})",
        "x");
    REQUIRE(parsed.find("car").cluster_cross_distance_m.has_value());
    CHECK(*parsed.find("car").cluster_cross_distance_m == 0.3);
    CHECK_THROWS_WITH(parse_class_config("{", "cfg.json"), Catch::Contains("cfg.json"));
    CHECK_THROWS_WITH(parse_class_config(R"({"classes": [], "clases": []})", "x"),
                      Catch::Contains("/clases: unknown member"));
}

TEST_CASE("instances: two cars become two oriented car entities on the fitted road", "[entities]") {
    const auto doc = extract_entities(test_scene(), test_palette(), StereoCamera{},
                                      options_with_bundled_config("instances"));
    std::vector<scene_schema::Entity> cars;
    int roads = 0;
    for (const auto& e : doc.entities) {
        CHECK(e.class_name != "sky");
        CHECK(e.point_count > 0);
        CHECK(e.confidence > 0.0);
        CHECK(e.confidence <= 1.0);
        if (e.class_name == "car") cars.push_back(e);
        if (e.class_name == "road") ++roads;
    }
    CHECK(roads == 1);
    REQUIRE(cars.size() == 2);
    std::sort(cars.begin(), cars.end(), [](const auto& a, const auto& b) { return a.z < b.z; });
    CHECK(cars[0].x == Approx(-3.5).margin(0.15));
    CHECK(cars[0].z == Approx(12.0).margin(0.15));
    CHECK(cars[1].x == Approx(3.5).margin(0.15));
    CHECK(cars[1].z == Approx(20.0).margin(0.15));
    for (const auto& c : cars) {
        CHECK(c.theta == Approx(-kPi / 2.0).margin(0.05));
        CHECK(c.L == Approx(4.2).margin(0.15));
        CHECK(c.W == Approx(1.8).margin(0.15));
        CHECK(c.y == Approx(1.65 - 0.75).margin(0.1));
        CHECK(c.id.rfind("car-", 0) == 0);
    }
    REQUIRE(doc.extra.contains("ground_plane"));
    CHECK(doc.extra["ground_plane"]["camera_height_m"].get<double>() == Approx(1.65).margin(0.02));
    scene_schema::EntityDocument full = doc;
    full.frame.id = "test";
    CHECK_NOTHROW(scene_schema::check(full));
}

TEST_CASE("a thing seen over too little of its prior face is dropped, its area taken at its points",
          "[entities]") {
    // Two upright faces 5 m ahead on the road, their points 1 cm apart (one pixel each at
    // f = 500 px): 0.6 x 0.6 m (0.36 m^2) and 0.8 x 0.7 m (0.56 m^2). 15 % of the car prior's
    // 1.8 x 1.5 m face is 0.405 m^2. The boxes are completed away from the camera, their centres
    // 2 m behind the faces: taken there, the smaller face would count twice its area.
    LabeledCloud cloud;
    add_road(cloud);
    const auto add_face = [&](float x, float width, float height) {
        for (float y = 1.55f - height; y <= 1.55f; y += 0.01f) {
            for (float a = 0.0f; a <= width; a += 0.01f) add_point(cloud, {x + a, y, 5.0f}, 2);
        }
    };
    add_face(-3.0f, 0.6f, 0.6f);
    add_face(2.5f, 0.8f, 0.7f);
    ExtractOptions options = options_with_bundled_config("instances");
    const auto cars = [&](const ExtractOptions& o) { return cars_of(cloud, o); };
    REQUIRE(cars(options).size() == 2);  // off by default
    options.min_face_share = 0.15;
    options.fx_px = 500.0;
    options.fy_px = 500.0;
    const auto kept = cars(options);
    REQUIRE(kept.size() == 1);
    CHECK(kept[0].x > 2.0);
    CHECK(kept[0].id == "car-1");
    CHECK(kept[0].z > 6.0);  // the box lies behind the face it was seen over
    options.fx_px = 0.0;     // no focal length: off
    CHECK(cars(options).size() == 2);
    options.min_face_share = 1.0;
    CHECK_THROWS_WITH(options.validate(), Catch::Contains("min_face_share"));
}

TEST_CASE("a car box whose top stays under the family's minimum height is no car", "[entities]") {
    // Two car-classed blocks 8 m ahead on the road, 1.8 m wide and 3 m long: one 1.4 m tall,
    // one 0.7 m (a low wall or a hedge the stereo-only rules called a car).
    LabeledCloud cloud;
    add_road(cloud);
    const auto add_block = [&](float x, float height) {
        for (float y = 1.65f - height; y <= 1.60f; y += 0.02f) {
            for (float a = 0.0f; a <= 1.8f; a += 0.02f) add_point(cloud, {x + a, y, 8.0f}, 2);
            for (float z = 8.0f; z <= 11.0f; z += 0.02f) add_point(cloud, {x, y, z}, 2);
        }
    };
    add_block(-4.5f, 1.4f);
    add_block(2.7f, 0.7f);
    ExtractOptions options = options_with_bundled_config("instances");
    const auto cars = [&](const ExtractOptions& o) { return cars_of(cloud, o); };
    REQUIRE(cars(options).size() == 2);  // off by default
    options.family_min_height_m = 0.9;
    const auto kept = cars(options);
    REQUIRE(kept.size() == 1);
    CHECK(kept[0].x < 0.0);
    CHECK(kept[0].H == Approx(1.4).margin(0.1));
    options.family_class = "";  // no family class: nothing is held to it
    CHECK(cars(options).size() == 2);
    options.family_min_height_m = -0.1;
    CHECK_THROWS_WITH(options.validate(), Catch::Contains("family_min_height_m"));
}

TEST_CASE("a gap's few high points between two cars in a row make no car of the next car's end",
          "[entities]") {
    // Two cars' right sides (x = -1.1) end to end 2.4 m apart: the near one's roof, then its
    // boot; in the gap, from 0.5 m on, 120 smeared points 1.7-1.9 m high (a tree's crown bled
    // onto the mask); then the far one's bonnet and roof. The far car's blob, gap included, is
    // cut at the valley of its bonnet: the piece before it is the gap and the bonnet's front,
    // boxed as a third car (and the far car's box pushed 0.4 m on) unless the cut moves to the
    // bonnet's front, leaving the gap's sparse points alone.
    LabeledCloud cloud;
    add_road(cloud);
    const auto add_side = [&](float z0, float z1, float top) {
        for (float y = 0.15f; y <= top + 1e-4f; y += 0.05f) {
            for (float z = z0; z < z1; z += 0.025f) add_point(cloud, {-1.1f, 1.65f - y, z}, 2);
        }
    };
    add_side(10.0f, 13.6f, 1.5f);  // near car: roof
    add_side(13.6f, 14.2f, 1.0f);  //           boot
    for (int k = 0; k < 120; ++k) {
        const auto f = static_cast<float>(k);
        add_point(cloud, {-1.1f, 1.65f - (1.7f + 0.0016f * f), 14.7f + 0.0147f * f}, 2);
    }
    for (int k = 0; k < 4; ++k) {  // the boot's smear just behind it, low
        add_point(cloud, {-1.1f, 1.65f - 0.4f, 14.3f + 0.1f * static_cast<float>(k)}, 2);
    }
    add_side(16.6f, 17.4f, 1.0f);  // far car: bonnet
    add_side(17.4f, 20.8f, 1.5f);  //          roof
    std::vector<scene_schema::Entity> cars = cars_of(cloud);
    REQUIRE(cars.size() == 2);
    std::sort(cars.begin(), cars.end(), [](const auto& a, const auto& b) { return a.z < b.z; });
    CHECK(cars[0].z == Approx(12.1).margin(0.3));
    CHECK(cars[1].z == Approx(18.7).margin(0.3));
}

TEST_CASE("a parked row merged into one blob is split into car-sized boxes", "[entities]") {
    LabeledCloud cloud;
    for (float x = -6.0f; x <= 6.0f; x += 0.25f) {
        for (float z = 3.0f; z <= 40.0f; z += 0.25f) add_point(cloud, {x, 1.65f, z}, 0);
    }
    // Three touching cars along z (bumper to bumper), seen from their right side only.
    for (float y = 0.15f; y <= 1.65f; y += 0.05f) {
        for (float z = 10.0f; z <= 22.6f; z += 0.05f) add_point(cloud, {-4.0f, y, z}, 2);
    }
    const auto doc = extract_entities(cloud, test_palette(), StereoCamera{},
                                      options_with_bundled_config("instances"));
    int cars = 0;
    for (const auto& e : doc.entities) {
        if (e.class_name != "car") continue;
        ++cars;
        CHECK(e.L < 5.5);
        CHECK(e.theta == Approx(-kPi / 2.0).margin(0.05));
    }
    CHECK(cars == 3);
}

TEST_CASE("the thesis extractors make one entity per class", "[entities]") {
    for (const char* method : {"centroid", "average", "variance"}) {
        const auto doc = extract_entities(test_scene(), test_palette(), StereoCamera{},
                                          options_with_bundled_config(method));
        int cars = 0;
        for (const auto& e : doc.entities) {
            CHECK(e.class_name != "sky");
            CHECK(e.theta == 0.0);
            CHECK(e.method == std::string(method));
            if (e.class_name == "car") {
                ++cars;
                CHECK(e.id == "car-1");
                // The mean of both cars lies between them.
                CHECK(e.x == Approx(0.0).margin(0.5));
            }
        }
        CHECK(cars == 1);
    }
}

TEST_CASE("extract options name the bad field", "[entities]") {
    ExtractOptions o;
    o.method = "magic";
    CHECK_THROWS_WITH(o.validate(), Catch::Contains("method"));
    o.method = "instances";
    o.max_range_m = 0.0;
    CHECK_THROWS_WITH(o.validate(), Catch::Contains("max_range_m"));
    o.max_range_m = 60.0;
    o.row_low_fraction = 1.0;
    CHECK_THROWS_WITH(o.validate(), Catch::Contains("row_low_fraction"));
    o.row_low_fraction = 0.7;
    o.row_low_extent_m = 0.0;
    CHECK_THROWS_WITH(o.validate(), Catch::Contains("row_low_extent_m"));
    o.row_low_extent_m = 0.6;
    o.row_gap_m = -0.1;
    CHECK_THROWS_WITH(o.validate(), Catch::Contains("row_gap_m"));
    o.row_gap_m = 0.6;
    o.row_valley_depth_m = -0.1;
    CHECK_THROWS_WITH(o.validate(), Catch::Contains("row_valley_depth_m"));
    o.row_valley_depth_m = 0.4;
    o.row_valley_bin_m = 0.0;
    CHECK_THROWS_WITH(o.validate(), Catch::Contains("row_valley_bin_m"));
    o.row_valley_bin_m = 0.15;
    o.strip_beside_width_px = -1.0;
    CHECK_THROWS_WITH(o.validate(), Catch::Contains("strip_beside_width_px"));
}

TEST_CASE("image-space clustering also separates two cars and keeps each whole", "[entities]") {
    // Give the scene a pixel grid: each point its own pixel, cars in separate image columns.
    LabeledCloud cloud = test_scene();
    cloud.width_px = 2000;
    cloud.height_px = 2000;
    for (std::size_t i = 0; i < cloud.size(); ++i) {
        const auto& p = cloud.xyz_m[i];
        // Pinhole projection with f = 500 px, principal point (1000, 1000).
        const long u = std::lround(500.0 * double{p.x()} / double{p.z()} + 1000.0);
        const long v = std::lround(500.0 * double{p.y()} / double{p.z()} + 1000.0);
        cloud.pixel[i] =
            static_cast<std::uint32_t>(std::clamp(v, 0L, 1999L) * 2000 + std::clamp(u, 0L, 1999L));
    }
    ExtractOptions o = options_with_bundled_config("instances");
    o.clustering = "image";
    o.image_radius_px = 3;
    const auto doc = extract_entities(cloud, test_palette(), StereoCamera{}, o);
    int cars = 0;
    for (const auto& e : doc.entities) {
        if (e.class_name != "car") continue;
        ++cars;
        CHECK(e.L == Approx(4.2).margin(0.15));
    }
    CHECK(cars == 2);
    o.clustering = "voxels";
    CHECK_THROWS_WITH(o.validate(), Catch::Contains("clustering"));
}

namespace {

/// Gives every point the pixel of a pinhole camera (f = 500 px, principal point (1000, 1000))
/// on a 2000 x 2000 grid.
void project_pixels(LabeledCloud& cloud) {
    cloud.width_px = 2000;
    cloud.height_px = 2000;
    for (std::size_t i = 0; i < cloud.size(); ++i) {
        const auto& p = cloud.xyz_m[i];
        const long u = std::lround(500.0 * double{p.x()} / double{p.z()} + 1000.0);
        const long v = std::lround(500.0 * double{p.y()} / double{p.z()} + 1000.0);
        cloud.pixel[i] =
            static_cast<std::uint32_t>(std::clamp(v, 0L, 1999L) * 2000 + std::clamp(u, 0L, 1999L));
    }
}

/// split_oversized with the bundled car settings, the default options with the cascade of rules
/// (row_model "rules") and no ground plane (and not cut by the image's edge) unless given.
instances::Split split_with_car_prior(const std::vector<Eigen::Vector3f>& pts,
                                      const instances::Indices& idx, const OrientedBox& box,
                                      const std::optional<GroundPlane>& ground = std::nullopt,
                                      bool truncated = false) {
    const auto config = load_class_config(std::string(STEREOSCENE_SOURCE_DIR) +
                                          "/assets/classes/entity_config.json");
    ExtractOptions options;
    options.row_model = "rules";  // these tests check the cascade's cuts
    return instances::split_oversized(pts, idx, box, config.find("car"), ground, options,
                                      truncated);
}

/// The 1.8 m wide box of a row at x = -1.1 along +z, centred at (y, z).
OrientedBox row_box_along_z(double y, double z, double length_m, double height_m) {
    OrientedBox box;
    box.centre_m = Eigen::Vector3d(-1.1, y, z);
    box.theta = -kPi / 2.0;  // along +z
    box.L_m = length_m;
    box.W_m = 1.8;
    box.H_m = height_m;
    return box;
}

/// A row's side face at x = -1.1 from z0 to z1 along z, from 0.3 m up to `top` above a road
/// 1.65 m below the camera, a point every 5 cm.
void add_side(std::vector<Eigen::Vector3f>& pts, float z0, float z1, float top) {
    for (float z = z0; z <= z1; z += 0.05f) {
        for (float h = 0.3f; h <= top; h += 0.05f) pts.emplace_back(-1.1f, 1.65f - h, z);
    }
}

/// Every index of pts, in order.
instances::Indices all_of(const std::vector<Eigen::Vector3f>& pts) {
    instances::Indices idx(pts.size());
    std::iota(idx.begin(), idx.end(), std::size_t{0});
    return idx;
}

/// Whether each piece of the split lies wholly before z = gap_lo or wholly after z = gap_hi.
bool parted_at(const std::vector<Eigen::Vector3f>& pts, const instances::Split& split, float gap_lo,
               float gap_hi) {
    for (const auto& part : split.parts) {
        float lo = std::numeric_limits<float>::max(), hi = -lo;
        for (std::size_t i : part) {
            lo = std::min(lo, pts[i].z());
            hi = std::max(hi, pts[i].z());
        }
        if (!(hi <= gap_lo || lo >= gap_hi)) return false;
    }
    return true;
}

int count_class(const scene_schema::EntityDocument& doc, const std::string& name) {
    int n = 0;
    for (const auto& e : doc.entities) n += e.class_name == name ? 1 : 0;
    return n;
}

}  // namespace

TEST_CASE("wrong matches interleaved with a near car's pixels are not a second car", "[entities]") {
    LabeledCloud cloud;
    for (float x = -6.0f; x <= 6.0f; x += 0.25f) {
        for (float z = 3.0f; z <= 40.0f; z += 0.25f) add_point(cloud, {x, 1.65f, z}, 0);
    }
    // The rear of a car 10 m ahead; every 10th of its pixels matched wrongly at twice the
    // depth (the same viewing ray, so the same pixel neighbourhood).
    int k = 0;
    for (float y = 0.15f; y <= 1.65f; y += 0.02f) {
        for (float x = -0.9f; x <= 0.9f; x += 0.02f) {
            const float scale = (k++ % 10 == 0) ? 2.0f : 1.0f;
            add_point(cloud, {x * scale, y * scale, 10.0f * scale}, 2);
        }
    }
    project_pixels(cloud);
    ExtractOptions o = options_with_bundled_config("instances");
    CHECK(count_class(extract_entities(cloud, test_palette(), StereoCamera{}, o), "car") == 1);
    o.shadow_fraction = 1.0;  // never suppress: the shadow becomes a second car
    CHECK(count_class(extract_entities(cloud, test_palette(), StereoCamera{}, o), "car") == 2);
}

namespace {

/// The rear face of a car 10 m ahead (x -0.9..0.9, 1.5 m high): pixels u 955-1045 and
/// v 1007-1082 for project_pixels' camera; optionally with a hole in x -0.7..0.7, y 0.4..1.4
/// (u 965-1035, v 1020-1070), where the dark body gave no disparity.
void add_near_rear(LabeledCloud& cloud, bool with_hole) {
    for (float y = 0.15f; y <= 1.65f; y += 0.02f) {
        for (float x = -0.9f; x <= 0.9f; x += 0.02f) {
            if (with_hole && std::abs(x) < 0.7f && y > 0.4f && y < 1.4f) continue;
            add_point(cloud, {x, y, 10.0f}, 2);
        }
    }
}

}  // namespace

TEST_CASE("wrong matches inside a hole of a nearer car's pixels are not a second car",
          "[entities][shadow]") {
    LabeledCloud cloud;
    add_road(cloud);
    add_near_rear(cloud, true);
    // Points 4 m behind, seen through the middle of the hole (u 975-1025, v 1030-1060): every
    // pixel at least 10 px from the car's own, but inside its extent on every row.
    for (float y = 0.84f; y <= 1.65f; y += 0.02f) {
        for (float x = -0.7f; x <= 0.7f; x += 0.02f) add_point(cloud, {x, y, 14.0f}, 2);
    }
    project_pixels(cloud);
    ExtractOptions o = options_with_bundled_config("instances");
    CHECK(count_class(extract_entities(cloud, test_palette(), StereoCamera{}, o), "car") == 1);
    o.shadow_fraction = 1.0;  // never suppress: the wrong matches become a second car
    CHECK(count_class(extract_entities(cloud, test_palette(), StereoCamera{}, o), "car") == 2);
}

TEST_CASE("a car partly hidden by a nearer one, seen right beside it, is kept",
          "[entities][shadow]") {
    LabeledCloud cloud;
    add_road(cloud);
    add_near_rear(cloud, false);
    // The rear of a car 18 m ahead, its right part hidden: only x -2.2..-1.65 is seen, 16 px
    // immediately left of the nearer car (u 939-954), a real object beside an occluder.
    for (float y = 0.15f; y <= 1.65f; y += 0.05f) {
        for (float x = -2.2f; x <= -1.65f; x += 0.02f) add_point(cloud, {x, y, 18.0f}, 2);
    }
    project_pixels(cloud);
    ExtractOptions o = options_with_bundled_config("instances");
    std::vector<scene_schema::Entity> cars;
    for (const auto& e : extract_entities(cloud, test_palette(), StereoCamera{}, o).entities) {
        if (e.class_name == "car") cars.push_back(e);
    }
    REQUIRE(cars.size() == 2);
    std::sort(cars.begin(), cars.end(), [](const auto& a, const auto& b) { return a.z < b.z; });
    CHECK(cars[1].z > 18.0);
    o.fragment_height_fraction = 1.0;  // every candidate a fragment: beside counts as a shadow
    CHECK(count_class(extract_entities(cloud, test_palette(), StereoCamera{}, o), "car") == 1);
}

TEST_CASE("a car's points on a depth edge count as its points but do not lengthen its box",
          "[entities]") {
    // A car's right side (x = -1.1) from z 10 to 14.2, 0.15-1.5 m high, and beyond its far end,
    // up to z 15.0, the upper half of the next car's rear face as the matcher places it where
    // it shows over the first car's roof: between the two. Flagged as a depth edge, those points
    // leave the box as the side alone makes it and still count as the car's. (Unflagged, the
    // row partition leaves them out as no thing's; the cascade of rules boxes them with the car.)
    LabeledCloud cloud;
    add_road(cloud);
    for (float y = 0.15f; y <= 1.5f + 1e-4f; y += 0.05f) {
        for (float z = 10.0f; z < 14.2f; z += 0.05f) add_point(cloud, {-1.1f, 1.65f - y, z}, 2);
    }
    LabeledCloud alone = cloud;
    project_pixels(alone);
    const std::size_t first_edge = cloud.size();
    for (float y = 0.9f; y <= 1.5f + 1e-4f; y += 0.05f) {
        for (float z = 14.2f; z < 15.0f; z += 0.05f) add_point(cloud, {-1.1f, 1.65f - y, z}, 2);
    }
    project_pixels(cloud);
    const auto car_of = [](const LabeledCloud& c, const std::string& row_model) {
        ExtractOptions o = options_with_bundled_config("instances");
        o.row_model = row_model;
        const std::vector<scene_schema::Entity> cars = cars_of(c, o);
        REQUIRE(cars.size() == 1);
        return cars[0];
    };
    for (const std::string row_model : {"partition", "rules"}) {
        INFO(row_model);
        LabeledCloud flagged = cloud;
        const scene_schema::Entity own = car_of(alone, row_model);
        if (row_model == "rules") {
            // Without the band, the cascade's box reaches over the edge's points.
            CHECK(car_of(cloud, row_model).L > own.L + 0.4);
        }
        flagged.depth_edge.assign(2000 * 2000, 0);
        for (std::size_t i = first_edge; i < flagged.size(); ++i) {
            flagged.depth_edge[flagged.pixel[i]] = 1;
        }
        const scene_schema::Entity car = car_of(flagged, row_model);
        CHECK(car.z == Approx(own.z).margin(0.01));
        CHECK(car.L == Approx(own.L).margin(0.01));
        CHECK(car.point_count > own.point_count);
    }
}

TEST_CASE("a thin strip of roof-line smear just above a nearer car is not a car",
          "[entities][shadow]") {
    LabeledCloud cloud;
    add_road(cloud);
    add_near_rear(cloud, false);
    // The pixels right above the car's roof (v 1001-1006, u 958-1042), matched to the
    // background 8 m behind: a strip 0.18 m high at roof height, 900 points.
    for (float y = 0.036f; y <= 0.216f; y += 0.03f) {
        for (float x = -1.5f; x <= 1.5f; x += 0.02f) add_point(cloud, {x, y, 18.0f}, 2);
    }
    project_pixels(cloud);
    ExtractOptions o = options_with_bundled_config("instances");
    CHECK(count_class(extract_entities(cloud, test_palette(), StereoCamera{}, o), "car") == 1);
    o.fragment_height_fraction = 0.0;  // no fragments: the strip lies on no row of the car
    CHECK(count_class(extract_entities(cloud, test_palette(), StereoCamera{}, o), "car") == 2);
    o.fragment_height_fraction = 1.5;
    CHECK_THROWS_WITH(o.validate(), Catch::Contains("fragment_height_fraction"));
}

TEST_CASE("a fragment whose box centre falls inside a larger car is dropped", "[entities]") {
    LabeledCloud cloud = test_scene();
    // A blob of car points 1 m behind the visible side of the first car (inside its body).
    for (float y = 0.8f; y <= 1.2f; y += 0.05f) {
        for (float x = -3.7f; x <= -3.3f; x += 0.05f) {
            for (float z = 11.8f; z <= 12.2f; z += 0.1f) add_point(cloud, {x, y, z}, 2);
        }
    }
    const auto doc = extract_entities(cloud, test_palette(), StereoCamera{},
                                      options_with_bundled_config("instances"));
    CHECK(count_class(doc, "car") == 2);
}

TEST_CASE("a parked row cut at clear gaps keeps every car although each hides the next",
          "[entities]") {
    LabeledCloud cloud;
    add_road(cloud);
    // Three cars parked along z, 0.5 m apart (one blob for the clustering), right sides seen:
    // in the image each farther car lies right beside the nearer one, as a shadow would.
    const std::vector<float> starts = {8.0f, 12.7f, 17.4f};
    add_row_sides(cloud, starts);
    project_pixels(cloud);
    const auto doc = extract_entities(cloud, test_palette(), StereoCamera{},
                                      options_with_bundled_config("instances"));
    std::vector<double> centres;
    for (const auto& e : doc.entities) {
        if (e.class_name == "car") centres.push_back(e.z);
    }
    std::sort(centres.begin(), centres.end());
    REQUIRE(centres.size() == 3);
    for (std::size_t k = 0; k < 3; ++k)
        CHECK(centres[k] == Approx(double{starts[k]} + 2.1).margin(0.3));
}

namespace {

/// The camera-facing part of a car heading along x, nose towards the camera at x = x_nose:
/// the front below the bonnet, the bonnet (0.9 m high, 1 m long), the windscreen and the roof
/// (1.5 m), 1.8 m wide around z_centre, on the road at y = 1.65.
void add_car_front_on(LabeledCloud& cloud, float x_nose, float z_centre) {
    for (float z = z_centre - 0.9f; z <= z_centre + 0.9f; z += 0.05f) {
        for (float h = 0.3f; h <= 0.9f; h += 0.05f) add_point(cloud, {x_nose, 1.65f - h, z}, 2);
        for (float x = x_nose; x <= x_nose + 1.0f; x += 0.05f) {
            add_point(cloud, {x, 1.65f - 0.9f, z}, 2);
        }
        for (float x = x_nose + 1.0f; x <= x_nose + 1.6f; x += 0.05f) {
            add_point(cloud, {x, 1.65f - (0.9f + (x - x_nose - 1.0f)), z}, 2);
        }
        for (float x = x_nose + 1.6f; x <= x_nose + 3.0f; x += 0.05f) {
            add_point(cloud, {x, 1.65f - 1.5f, z}, 2);
        }
    }
}

/// The camera-facing part of a car heading along z from z0 to z1, its left side at x = 4.35
/// seen: door (up to 1 m), 0.2 m of window rising to the roof (1.45 m) across the rest of the
/// width (to x = 5.9), on the road at y = 1.65.
void add_car_side_on(LabeledCloud& cloud, float z0, float z1) {
    for (float z = z0; z <= z1; z += 0.05f) {
        for (float h = 0.3f; h <= 1.0f; h += 0.05f) add_point(cloud, {4.35f, 1.65f - h, z}, 2);
        for (float x = 4.35f; x <= 4.55f; x += 0.05f) {
            add_point(cloud, {x, 1.65f - (1.0f + 2.0f * (x - 4.35f)), z}, 2);
        }
        for (float x = 4.55f; x <= 5.9f; x += 0.05f) add_point(cloud, {x, 1.65f - 1.45f, z}, 2);
    }
}

/// Road points (class 0) on y = 1.65 over x in [-6, 10], z in [3, 40], every 0.25 m.
LabeledCloud road_cloud() {
    LabeledCloud cloud;
    for (float x = -6.0f; x <= 10.0f; x += 0.25f) {
        for (float z = 3.0f; z <= 40.0f; z += 0.25f) add_point(cloud, {x, 1.65f, z}, 0);
    }
    return cloud;
}

}  // namespace

TEST_CASE("two cars side by side seen front-on become two cars heading across the blob",
          "[entities][split]") {
    LabeledCloud cloud = road_cloud();
    // Noses at x = 4.35 (centres at x = 6.5 for 4.3 m cars), 0.3 m apart: one blob 3.9 m long
    // along z, as long as one car seen side-on, but with bonnets in front of the roofs.
    add_car_front_on(cloud, 4.35f, 7.0f);
    add_car_front_on(cloud, 4.35f, 9.1f);
    ExtractOptions o = options_with_bundled_config("instances");
    std::vector<scene_schema::Entity> cars;
    for (const auto& e : extract_entities(cloud, test_palette(), StereoCamera{}, o).entities) {
        if (e.class_name == "car") cars.push_back(e);
    }
    std::sort(cars.begin(), cars.end(), [](const auto& a, const auto& b) { return a.z < b.z; });
    REQUIRE(cars.size() == 2);
    const double z_true[] = {7.0, 9.1};
    for (std::size_t k = 0; k < 2; ++k) {
        CHECK(std::abs(std::sin(cars[k].theta)) < std::sin(10.0 * kPi / 180.0));
        CHECK(cars[k].x == Approx(6.5).margin(0.4));
        CHECK(cars[k].z == Approx(z_true[k]).margin(0.3));
    }
    o.row_low_fraction = 0.0;  // off: one car heading along z
    CHECK(count_class(extract_entities(cloud, test_palette(), StereoCamera{}, o), "car") == 1);
}

TEST_CASE("a vehicle seen side-on with something low before one end is not a row front-on",
          "[entities][split]") {
    LabeledCloud cloud = road_cloud();
    // A 6 m vehicle heading along z, its side at x = 4.35 seen as in the test below, and the
    // back of something low (0.3-0.7 m, like the boot of a car beyond the blob's end) 0.1-0.9 m
    // nearer the camera beside its last metre. Over the whole blob the side nearer the camera
    // is low for 0.8 m, as a front-on row's bonnets are; slice by slice only the last is.
    add_car_side_on(cloud, 12.0f, 18.0f);
    for (float z = 17.0f; z <= 18.0f; z += 0.05f) {
        for (float x = 3.45f; x <= 4.25f; x += 0.05f) {
            for (float h = 0.3f; h <= 0.7f; h += 0.05f) add_point(cloud, {x, 1.65f - h, z}, 2);
        }
    }
    const auto doc = extract_entities(cloud, test_palette(), StereoCamera{},
                                      options_with_bundled_config("instances"));
    for (const auto& e : doc.entities) {
        // No box heading across the blob (a front-on row's pieces head along x).
        if (e.class_name == "car")
            CHECK(std::abs(std::cos(e.theta)) < std::sin(20.0 * kPi / 180.0));
    }
    CHECK(count_class(doc, "car") >= 1);
}

TEST_CASE("a car seen side-on, its roof right behind the door line, is not cut across",
          "[entities][split]") {
    LabeledCloud cloud = road_cloud();
    // Heading along z, left side at x = 4.35 seen: door (up to 1 m), 0.2 m of window rising
    // to the roof (1.45 m) across the rest of the width. Low only over 0.2 m from the camera.
    add_car_side_on(cloud, 12.0f, 16.2f);
    ExtractOptions o = options_with_bundled_config("instances");
    const auto doc = extract_entities(cloud, test_palette(), StereoCamera{}, o);
    REQUIRE(count_class(doc, "car") == 1);
    for (const auto& e : doc.entities) {
        if (e.class_name == "car") CHECK(e.theta == Approx(-kPi / 2.0).margin(0.05));
    }
    o.row_low_extent_m = 0.1;  // a low band this narrow would count as bonnets
    CHECK(count_class(extract_entities(cloud, test_palette(), StereoCamera{}, o), "car") == 2);
}

TEST_CASE("a parked row whose far car is half hidden is cut at its gaps walked from the near end",
          "[entities][split]") {
    LabeledCloud cloud;
    for (float x = -6.0f; x <= 6.0f; x += 0.25f) {
        for (float z = 3.0f; z <= 40.0f; z += 0.25f) add_point(cloud, {x, 1.65f, z}, 0);
    }
    // Sides of three cars 0.45 m apart (one blob); only the first 2 m of the third are seen.
    // An even division of the seen 11.4 m would cut the second car short.
    const double starts[] = {8.0, 12.65, 17.3};
    const float ends[] = {12.2f, 16.85f, 19.3f};
    for (int k = 0; k < 3; ++k) {
        for (float y = 0.15f; y <= 1.65f; y += 0.05f) {
            for (float z = starts[k]; z <= ends[k]; z += 0.05f) add_point(cloud, {-1.1f, y, z}, 2);
        }
    }
    project_pixels(cloud);
    const auto doc = extract_entities(cloud, test_palette(), StereoCamera{},
                                      options_with_bundled_config("instances"));
    std::vector<double> centres;
    for (const auto& e : doc.entities) {
        if (e.class_name == "car") centres.push_back(e.z);
    }
    std::sort(centres.begin(), centres.end());
    REQUIRE(centres.size() == 3);
    for (int k = 0; k < 3; ++k) CHECK(centres[k] == Approx(starts[k] + 2.1).margin(0.3));
}

TEST_CASE("a parked row's walk of cuts starts at its first car, not at points smeared before it",
          "[entities][split]") {
    LabeledCloud cloud;
    add_road(cloud);
    // Three cars' sides 0.45 m apart, and a sparse trail of wrong matches smeared 2.5 m towards
    // the camera from the first: a walk from the trail's end cuts the first car in its middle.
    const std::vector<float> starts = {8.0f, 12.65f, 17.3f};
    add_row_sides(cloud, starts);
    for (float z = 5.5f; z < 8.0f; z += 0.2f) {
        for (float y = 0.6f; y <= 1.2f; y += 0.3f) add_point(cloud, {-1.1f, y, z}, 2);
    }
    project_pixels(cloud);
    const auto doc = extract_entities(cloud, test_palette(), StereoCamera{},
                                      options_with_bundled_config("instances"));
    std::vector<std::pair<double, double>> spans;  // along z
    for (const auto& e : doc.entities) {
        if (e.class_name == "car") spans.emplace_back(e.z - e.L / 2.0, e.z + e.L / 2.0);
    }
    std::sort(spans.begin(), spans.end());
    REQUIRE(spans.size() == 3);
    for (int k = 0; k < 3; ++k) {
        CHECK(spans[k].first == Approx(starts[k]).margin(0.3));
        CHECK(spans[k].second == Approx(double{starts[k]} + 4.2).margin(0.3));
    }
}

TEST_CASE("a parked row's walk of cuts starts again where a wide gap in the row ends",
          "[entities][split]") {
    // Two pairs of cars 0.45 m apart, the pairs 3 m apart (a driveway) and joined by a trail
    // of wrong matches; the first 2 m of the last car seen. A walk that steps one car length
    // on from its cut in the driveway cuts the third car in its middle, and so does an even
    // division of the row.
    const std::vector<float> starts = {8.0f, 12.65f, 19.85f, 24.5f};
    const std::vector<float> ends = {12.2f, 16.85f, 24.05f, 26.5f};
    std::vector<Eigen::Vector3f> pts;
    for (std::size_t k = 0; k < starts.size(); ++k) {
        for (float y = 0.15f; y <= 1.65f; y += 0.05f) {
            for (float z = starts[k]; z <= ends[k]; z += 0.05f) pts.emplace_back(-1.1f, y, z);
        }
    }
    for (float z = 16.9f; z < 19.85f; z += 0.3f) pts.emplace_back(-1.1f, 0.5f, z);
    instances::Indices idx(pts.size());
    std::iota(idx.begin(), idx.end(), std::size_t{0});
    const auto split = split_with_car_prior(pts, idx, row_box_along_z(0.9, 17.25, 18.5, 1.5));
    std::vector<std::pair<float, float>> spans;  // 2-98 % of each piece along z
    for (const auto& part : split.parts) {
        std::vector<float> z;
        for (std::size_t i : part) z.push_back(pts[i].z());
        std::sort(z.begin(), z.end());
        if (z.size() > 100) spans.emplace_back(z[z.size() / 50], z[z.size() - 1 - z.size() / 50]);
    }
    std::sort(spans.begin(), spans.end());
    REQUIRE(spans.size() == 4);
    for (std::size_t k = 0; k < 4; ++k) {
        CHECK(spans[k].first == Approx(starts[k]).margin(0.2));
        CHECK(spans[k].second == Approx(ends[k]).margin(0.2));
    }
}

TEST_CASE("a parked row's walk of cuts steps a van's length over a van when a car's finds no gap",
          "[entities][split]") {
    // The end of a car the row's first cut left in (1 m, 1 m high, touching), a van 2 m high,
    // a car, the first 2 m of another, 0.45 m apart. One car's pitch from the row's start
    // falls inside the van, with no gap within reach of it; the van's pitch reaches its end.
    const std::vector<float> starts = {6.8f, 7.8f, 13.45f, 18.1f};
    const std::vector<float> ends = {7.8f, 13.0f, 17.65f, 20.1f};
    const std::vector<float> tops = {1.0f, 2.0f, 1.5f, 1.5f};
    std::vector<Eigen::Vector3f> pts;
    for (std::size_t k = 0; k < starts.size(); ++k) {
        for (float h = 0.3f; h <= tops[k]; h += 0.05f) {
            for (float z = starts[k]; z <= ends[k]; z += 0.05f) {
                pts.emplace_back(-1.1f, 1.65f - h, z);
            }
        }
    }
    instances::Indices idx(pts.size());
    std::iota(idx.begin(), idx.end(), std::size_t{0});
    const auto split =
        split_with_car_prior(pts, idx, row_box_along_z(0.65, 13.45, 13.3, 2.0), GroundPlane{});
    std::vector<std::pair<float, float>> spans;  // each piece along z
    for (const auto& part : split.parts) {
        float lo = std::numeric_limits<float>::max(), hi = -lo;
        for (std::size_t i : part) {
            lo = std::min(lo, pts[i].z());
            hi = std::max(hi, pts[i].z());
        }
        spans.emplace_back(lo, hi);
    }
    std::sort(spans.begin(), spans.end());
    REQUIRE(spans.size() == 3);
    CHECK(spans[0].first == Approx(6.8f).margin(0.1));
    CHECK(spans[0].second == Approx(13.0f).margin(0.1));  // the van whole, with the car's end
    CHECK(spans[1].first == Approx(13.45f).margin(0.1));
    CHECK(spans[1].second == Approx(17.65f).margin(0.1));
    CHECK(spans[2].first == Approx(18.1f).margin(0.1));
}

TEST_CASE(
    "a parked row's walk of cuts steps over the dip under a van's lower rear to the gap "
    "behind it",
    "[entities][split]") {
    // A van (roof 2.0 m) whose side thins out for 0.3 m one car's pitch on, where its lower
    // rear (1.1 m) starts, then a 1.2 m gap whose first half holds smear, then two cars. The
    // dip is the emptiest place within reach of a car's pitch, but a wider gap lies within
    // reach of a van's: the van ends there, its lower rear with it.
    std::vector<Eigen::Vector3f> pts;
    add_side(pts, 12.0f, 15.9f, 2.0f);
    for (float z = 15.95f; z < 16.2f; z += 0.05f) pts.emplace_back(-1.1f, 0.55f, z);
    add_side(pts, 16.2f, 17.4f, 1.1f);
    for (float z = 17.45f; z < 18.0f; z += 0.05f) {
        pts.emplace_back(-1.1f, 0.55f, z);
        pts.emplace_back(-1.1f, 0.6f, z);
    }
    add_side(pts, 18.6f, 22.8f, 1.45f);
    add_side(pts, 23.3f, 26.0f, 1.45f);
    const auto split = split_with_car_prior(pts, all_of(pts),
                                            row_box_along_z(0.65, 19.0, 14.0, 2.0), GroundPlane{});
    REQUIRE(split.parts.size() == 3);
    CHECK(parted_at(pts, split, 18.0f, 18.6f));
    CHECK(parted_at(pts, split, 22.8f, 23.3f));
    // A tall thing 3.9 m long, a clear 0.3 m gap one car's pitch on and the next car's side
    // where a van's pitch reaches, no gap there: the car's pitch cuts, at that gap.
    pts.clear();
    add_side(pts, 12.0f, 15.9f, 2.0f);
    add_side(pts, 16.2f, 20.4f, 1.45f);
    add_side(pts, 20.9f, 25.1f, 1.45f);
    const auto plain = split_with_car_prior(pts, all_of(pts),
                                            row_box_along_z(0.65, 18.55, 13.1, 2.0), GroundPlane{});
    REQUIRE(plain.parts.size() == 3);
    CHECK(parted_at(pts, plain, 15.9f, 16.2f));
    CHECK(parted_at(pts, plain, 20.4f, 20.9f));
}

TEST_CASE("a car box longer than a van is cut at a clear gap between a van and a lower car",
          "[entities][split]") {
    // The last 2.2 m of a small car (roof 1.35 m, boot 1.0 m), 0.6 m apart from a van whose
    // bonnet (1.1 m) and first 2.6 m of roof (2.0 m) show: 6.4 m, over a van's pitch and under
    // a row's walk (1.6 car lengths), the valley between the roofs too shallow to cut.
    std::vector<Eigen::Vector3f> pts;
    add_side(pts, 10.0f, 11.2f, 1.35f);
    add_side(pts, 11.25f, 12.2f, 1.0f);
    add_side(pts, 12.8f, 13.8f, 1.1f);
    add_side(pts, 13.85f, 16.4f, 2.0f);
    const auto split = split_with_car_prior(pts, all_of(pts), row_box_along_z(0.65, 13.2, 6.4, 2.0),
                                            GroundPlane{});
    REQUIRE(split.parts.size() == 2);
    CHECK(parted_at(pts, split, 12.2f, 12.8f));
    // One car seen 6.4 m long, a gap before its bonnet's smear (2.2 m at 0.9 m): no piece
    // reaches a van's height, and the bonnet is no roof.
    pts.clear();
    add_side(pts, 10.0f, 13.6f, 1.45f);
    add_side(pts, 14.2f, 16.4f, 0.9f);
    CHECK(split_with_car_prior(pts, all_of(pts), row_box_along_z(0.65, 13.2, 6.4, 1.45),
                               GroundPlane{})
              .parts.size() == 1);
}

TEST_CASE("two small cars end to end boxed longer than a van are cut at the gap between roofs",
          "[entities][split]") {
    // What shows of two small cars 0.6 m apart at 25-30 m, smear filling the valley between
    // their roofs: 2.2 m (roof 1.35 m) and 3.6 m (roof 1.45 m), 6.4 m in all.
    std::vector<Eigen::Vector3f> pts;
    add_side(pts, 10.0f, 12.2f, 1.35f);
    add_side(pts, 12.8f, 16.4f, 1.45f);
    const auto split = split_with_car_prior(pts, all_of(pts),
                                            row_box_along_z(0.65, 13.2, 6.4, 1.45), GroundPlane{});
    REQUIRE(split.parts.size() == 2);
    CHECK(parted_at(pts, split, 12.2f, 12.8f));
    // The near piece only 1.5 m long (a car's end, no roof of its own): one thing.
    pts.clear();
    add_side(pts, 10.0f, 11.5f, 1.35f);
    add_side(pts, 12.1f, 16.4f, 1.45f);
    CHECK(split_with_car_prior(pts, all_of(pts), row_box_along_z(0.65, 13.2, 6.4, 1.45),
                               GroundPlane{})
              .parts.size() == 1);
}

TEST_CASE(
    "a row cut by the image's edge is parted where its near piece is one car, not at smear "
    "beyond",
    "[entities][split][truncation]") {
    // What shows of a car cut by the left edge (1.2 m of its side), a 0.4 m notch, the next car
    // (3.8 m), then 0.8 m on a sliver of smear: 6.5 m in all. The smear's gap is the widest,
    // but cut there the near piece (5.4 m) still holds both cars.
    std::vector<Eigen::Vector3f> pts;
    add_side(pts, 5.6f, 6.8f, 1.4f);
    add_side(pts, 7.2f, 11.0f, 1.45f);
    add_side(pts, 11.8f, 12.1f, 1.4f);
    const OrientedBox box = row_box_along_z(0.65, 8.85, 6.5, 1.45);
    const auto split = split_with_car_prior(pts, all_of(pts), box, std::nullopt, true);
    REQUIRE(split.parts.size() == 2);
    CHECK(parted_at(pts, split, 6.8f, 7.2f));
    // Not cut by the edge: no reason to part it.
    CHECK(split_with_car_prior(pts, all_of(pts), box).parts.size() == 1);
}

TEST_CASE("a walk of cuts crosses stray points smeared into the gap behind a van",
          "[entities][split]") {
    // A van (10-15.2 m, roof 2.0 m), 0.2 m of its smear at 15.5 m, a 2.3 m gap, then two cars
    // 0.4 m apart (18-21.6 m and 22-26.5 m): the next car starts where the gap ends, not
    // where the smear does.
    std::vector<Eigen::Vector3f> pts;
    add_side(pts, 10.0f, 15.2f, 2.0f);
    add_side(pts, 15.5f, 15.7f, 1.0f);
    add_side(pts, 18.0f, 21.6f, 1.45f);
    add_side(pts, 22.0f, 26.5f, 1.45f);
    const auto split = split_with_car_prior(pts, all_of(pts),
                                            row_box_along_z(0.65, 18.25, 16.5, 2.0), GroundPlane{});
    REQUIRE(split.parts.size() == 3);
    for (const auto& part : split.parts) {
        bool first_car = false, second_car = false, van = false;
        for (std::size_t i : part) {
            van = van || pts[i].z() <= 15.2f;
            first_car = first_car || (pts[i].z() >= 18.0f && pts[i].z() <= 21.6f);
            second_car = second_car || pts[i].z() >= 22.0f;
        }
        CHECK(int{van} + int{first_car} + int{second_car} == 1);  // one thing per piece
    }
}

TEST_CASE("two faint pieces of a row end to end are joined into one thing", "[entities][split]") {
    const auto config = load_class_config(std::string(STEREOSCENE_SOURCE_DIR) +
                                          "/assets/classes/entity_config.json");
    const ClassSettings& car = config.find("car");
    ExtractOptions options;
    options.min_face_share = 0.15;  // 0.405 m2 of a car's 1.8 x 1.5 m face
    options.fx_px = options.fy_px = 721.0;
    // A side at x = -4.8 along z, 25 m away: each point covers (25 / 721)^2 = 0.0012 m2.
    std::vector<Eigen::Vector3f> pts;
    const auto piece = [&](float z0, float z1, int rows) {
        instances::Candidate c;
        c.box.theta = -kPi / 2.0;  // along +z
        const float step = (z1 - z0) / 24.0f;
        for (int k = 0; k < 25; ++k) {
            for (int r = 0; r < rows; ++r) {
                c.members.push_back(pts.size());
                pts.emplace_back(-4.8f, 1.5f - 0.1f * r, z0 + step * k);
            }
        }
        return c;
    };
    const auto area = [&](const instances::Candidate& c) {
        return instances::seen_area_m2(pts, c.members, options.fx_px, options.fy_px);
    };
    // The first metre of a car (150 points, 0.18 m2) and the rest of what shows of it
    // (250 points, 0.30 m2), 0.3 m apart: neither is a thing, together they are.
    std::vector<instances::Candidate> candidates = {piece(23.0f, 24.0f, 6),
                                                    piece(24.3f, 26.0f, 10)};
    REQUIRE(area(candidates[0]) < min_seen_area_m2(car, options));
    REQUIRE(area(candidates[1]) < min_seen_area_m2(car, options));
    auto joined = instances::join_faint_pieces(pts, candidates, car, options);
    REQUIRE(joined.size() == 1);
    CHECK(joined[0].size() == 400);
    CHECK(candidates.empty());
    // 1 m apart (more than a row's gap): two things, or smear, not one cut in two.
    pts.clear();
    candidates = {piece(22.3f, 23.3f, 6), piece(24.3f, 26.0f, 10)};
    CHECK(instances::join_faint_pieces(pts, candidates, car, options).empty());
    CHECK(candidates.size() == 2);
    // Together still faint: fragments, left to be dropped.
    pts.clear();
    candidates = {piece(23.0f, 24.0f, 4), piece(24.3f, 26.0f, 4)};
    CHECK(instances::join_faint_pieces(pts, candidates, car, options).empty());
    // A faint piece beside a thing is the thing's business (shadows, strips), not a join.
    pts.clear();
    candidates = {piece(23.0f, 24.0f, 6), piece(24.3f, 26.0f, 20)};
    REQUIRE(area(candidates[1]) >= min_seen_area_m2(car, options));
    CHECK(instances::join_faint_pieces(pts, candidates, car, options).empty());
}

namespace {

/// The right side of a thing heading along z from z0 to z1, seen from x = 0 at x = -1.1:
/// heights up to top(z) above the road y = 1.65, every 5 cm.
template <typename Top>
void add_side(LabeledCloud& cloud, float z0, float z1, Top top) {
    for (float z = z0; z <= z1; z += 0.05f) {
        for (float h = 0.3f; h <= top(z - z0); h += 0.05f) {
            add_point(cloud, {-1.1f, 1.65f - h, z}, 2);
        }
    }
}

}  // namespace

TEST_CASE("a car and the front of the next one are cut at the valley between their roofs",
          "[entities][split]") {
    LabeledCloud cloud;
    for (float x = -6.0f; x <= 6.0f; x += 0.25f) {
        for (float z = 3.0f; z <= 40.0f; z += 0.25f) add_point(cloud, {x, 1.65f, z}, 0);
    }
    // A 4.5 m car (bonnet 0.85 m high for 0.9 m, roof 1.45 m, boot 1.0 m for the last 0.7 m),
    // 0.3 m behind it the first 1.8 m of the next (its bonnet, then roof; the rest hidden).
    // One blob 6.6 m long: too short for two priors, so a cut at the prior length never falls.
    add_side(cloud, 10.0f, 14.5f,
             [](float a) { return a < 0.9f ? 0.85f : (a < 3.8f ? 1.45f : 1.0f); });
    add_side(cloud, 14.8f, 16.6f, [](float a) { return a < 0.8f ? 0.85f : 1.45f; });
    project_pixels(cloud);
    ExtractOptions o = options_with_bundled_config("instances");
    // The sides are sampled evenly in metres, not as a camera's pixels (which thin out with
    // the square of the range): the boxes take their extents over points.
    o.area_weighted_extents = false;
    const auto cars_of = [&](const ExtractOptions& options) {
        std::vector<scene_schema::Entity> cars;
        for (const auto& e :
             extract_entities(cloud, test_palette(), StereoCamera{}, options).entities) {
            if (e.class_name == "car") cars.push_back(e);
        }
        std::sort(cars.begin(), cars.end(), [](const auto& a, const auto& b) { return a.z < b.z; });
        return cars;
    };
    for (const std::string row_model : {"partition", "rules"}) {
        INFO(row_model);
        o.row_model = row_model;
        const auto cars = cars_of(o);
        REQUIRE(cars.size() == 2);
        // The first box ends at the gap, the second starts there (each within 0.3 m).
        CHECK(cars[0].z - cars[0].L / 2.0 == Approx(10.0).margin(0.3));
        CHECK(cars[0].z + cars[0].L / 2.0 == Approx(14.5).margin(0.3));
        CHECK(cars[1].z - cars[1].L / 2.0 == Approx(14.8).margin(0.3));
    }
    o.row_valley_depth_m = 0.0;  // the cascade's valley cut off: one box over both
    CHECK(cars_of(o).size() == 1);
}

namespace {

/// Two cars' sides at x = -1.1 seen densely (z 8-12.2 and 12.65-16.85 m, 0.45 m apart), then a
/// third seen sparsely: `heights` rows of points from y = `y0` every `dy`, each `columns`
/// points from z = 17.3 m every 0.2 m.
void add_sparse_third_car(LabeledCloud& cloud, int heights, float y0, float dy, int columns) {
    for (float y = 0.15f; y <= 1.65f; y += 0.05f) {
        for (float z = 8.0f; z <= 12.2f; z += 0.05f) add_point(cloud, {-1.1f, y, z}, 2);
        for (float z = 12.65f; z <= 16.85f; z += 0.05f) add_point(cloud, {-1.1f, y, z}, 2);
    }
    for (int i = 0; i < heights; ++i) {
        for (int k = 0; k < columns; ++k) {
            add_point(cloud, {-1.1f, y0 + dy * static_cast<float>(i), 17.3f + 0.2f * k}, 2);
        }
    }
}

}  // namespace

TEST_CASE("the sparse far car of a parked row needs only half the class's minimum of points",
          "[entities][split]") {
    LabeledCloud cloud;
    for (float x = -6.0f; x <= 6.0f; x += 0.25f) {
        for (float z = 3.0f; z <= 40.0f; z += 0.25f) add_point(cloud, {x, 1.65f, z}, 0);
    }
    // Two cars seen densely, 0.45 m apart, then 66 points (< 100, the car minimum) of a third.
    add_sparse_third_car(cloud, 6, 0.3f, 0.25f, 11);
    project_pixels(cloud);
    const auto doc = extract_entities(cloud, test_palette(), StereoCamera{},
                                      options_with_bundled_config("instances"));
    std::vector<double> centres;
    for (const auto& e : doc.entities) {
        if (e.class_name == "car") centres.push_back(e.z);
    }
    std::sort(centres.begin(), centres.end());
    REQUIRE(centres.size() == 3);
    CHECK(centres[2] == Approx(17.3 + 2.1).margin(0.3));
}

TEST_CASE("two sparse cars past the end of a dense row's profile are two cars",
          "[entities][split]") {
    LabeledCloud cloud;
    for (float x = -6.0f; x <= 6.0f; x += 0.25f) {
        for (float z = 3.0f; z <= 40.0f; z += 0.25f) add_point(cloud, {x, 1.65f, z}, 0);
    }
    // Two sides seen densely (26k points), then, 0.45 m apart, a side seen sparsely (300
    // points) and a sparser one (under half a percent of the row: past its profile's end).
    for (float y = 0.15f; y <= 1.65f; y += 0.05f) {
        for (float z = 8.0f; z <= 12.2f; z += 0.01f) add_point(cloud, {-1.1f, y, z}, 2);
        for (float z = 12.65f; z <= 16.85f; z += 0.01f) add_point(cloud, {-1.1f, y, z}, 2);
    }
    for (int i = 0; i < 7; ++i) {
        for (int k = 0; k < 43; ++k) {
            add_point(cloud, {-1.1f, 0.3f + 0.2f * static_cast<float>(i), 17.3f + 0.1f * k}, 2);
        }
    }
    for (int i = 0; i < 4; ++i) {
        for (int k = 0; k < 29; ++k) {
            add_point(cloud, {-1.1f, 0.2f + 0.3f * static_cast<float>(i), 21.95f + 0.15f * k}, 2);
        }
    }
    project_pixels(cloud);
    ExtractOptions o = options_with_bundled_config("instances");
    o.row_model = "partition";  // its second look at a piece longer than a row's split length
    std::vector<scene_schema::Entity> cars = cars_of(cloud, o);
    std::sort(cars.begin(), cars.end(), [](const auto& a, const auto& b) { return a.z < b.z; });
    REQUIRE(cars.size() == 4);
    CHECK(cars[2].z == Approx(17.3 + 2.1).margin(0.6));
    CHECK(cars[3].z == Approx(21.95 + 2.1).margin(0.6));
    for (const auto& car : cars) CHECK(car.L < 5.0);
}

TEST_CASE("stuff points smeared onto a thing do not become a stuff entity on it",
          "[entities][stuff]") {
    Palette palette = test_palette();
    palette.classes.push_back({"building", 11, false, {70, 70, 70}});
    LabeledCloud cloud = test_scene();
    // A real building front along x = -8, and 1014 building points inside the first car's box
    // (x -3.5, z 12): the building's label spilling over the car's silhouette, at its depth.
    for (float z = 5.0f; z <= 25.0f; z += 0.25f) {
        for (float y = -3.0f; y <= 1.65f; y += 0.25f) add_point(cloud, {-8.0f, y, z}, 3);
    }
    for (float x = -3.8f; x <= -3.2f; x += 0.05f) {
        for (float z = 11.7f; z <= 12.3f; z += 0.05f) {
            for (float y = 0.65f; y <= 1.15f; y += 0.1f) add_point(cloud, {x, y, z}, 3);
        }
    }
    ExtractOptions o = options_with_bundled_config("instances");
    auto doc = extract_entities(cloud, palette, StereoCamera{}, o);
    REQUIRE(count_class(doc, "building") == 1);
    CHECK(count_class(doc, "car") == 2);
    for (const auto& e : doc.entities) {
        if (e.class_name != "building") continue;
        CHECK(e.id == "building-1");
        CHECK(e.x == Approx(-8.0).margin(0.3));
    }
    o.stuff_on_thing_fraction = 1.0;  // off: the spilled points make a second building
    CHECK(count_class(extract_entities(cloud, palette, StereoCamera{}, o), "building") == 2);
    o.stuff_on_thing_fraction = 0.0;
    CHECK_THROWS_WITH(o.validate(), Catch::Contains("stuff_on_thing_fraction"));
}

TEST_CASE("classes extracted on several threads give the same entities as on one", "[entities]") {
    ExtractOptions o = options_with_bundled_config("instances");
    o.threads = 1;
    const auto one = extract_entities(test_scene(), test_palette(), StereoCamera{}, o);
    REQUIRE(one.entities.size() >= 3);  // road and two cars
    for (int threads : {2, 3, 8}) {
        o.threads = threads;
        const auto many = extract_entities(test_scene(), test_palette(), StereoCamera{}, o);
        CHECK(scene_schema::dump(many) == scene_schema::dump(one));
    }
    o.threads = 0;
    CHECK_THROWS_WITH(o.validate(), Catch::Contains("threads"));
}

TEST_CASE("a large cloud split by class on several threads gives the entities of one thread",
          "[entities]") {
    // 20 m x 40 m of road at 0.05 m (about 320k points, so the split runs in several chunks),
    // two cars, and behind-the-camera points of both classes between them (dropped by the range
    // check, leaving gaps the chunks must close).
    LabeledCloud cloud;
    std::size_t road_points = 0;
    for (float x = -10.0f; x <= 10.0f; x += 0.05f) {
        for (float z = 3.0f; z <= 43.0f; z += 0.05f) {
            add_point(cloud, {x, 1.65f, z}, 0);
            ++road_points;
        }
        add_point(cloud, {x, 1.65f, -1.0f}, 0);
        add_point(cloud, {x, 1.0f, -1.0f}, 2);
    }
    add_car(cloud, -3.5f, 12.0f);
    add_car(cloud, 3.5f, 20.0f);
    REQUIRE(cloud.size() > 4 * 32768);
    ExtractOptions o = options_with_bundled_config("instances");
    o.threads = 1;
    const auto one = extract_entities(cloud, test_palette(), StereoCamera{}, o);
    REQUIRE(count_class(one, "car") == 2);
    REQUIRE(count_class(one, "road") == 1);
    for (const auto& e : one.entities) {
        if (e.class_name == "road") CHECK(e.point_count == static_cast<std::int64_t>(road_points));
    }
    for (int threads : {2, 3, 4}) {
        o.threads = threads;
        const auto many = extract_entities(cloud, test_palette(), StereoCamera{}, o);
        CHECK(scene_schema::dump(many) == scene_schema::dump(one));
    }
}

TEST_CASE("stuff taken every fourth pixel column gives the box and point count of every column",
          "[entities]") {
    // A road seen as a 400 x 300 pixel image (x across the columns, z along the rows), and a
    // car on it; the cloud knows its pixels. Road is stuff (column_step 4 in the bundled
    // config), the car a thing (every point).
    constexpr int kWidth = 400, kHeight = 300;
    LabeledCloud cloud;
    cloud.width_px = kWidth;
    cloud.height_px = kHeight;
    for (int v = 0; v < kHeight; ++v) {
        for (int u = 0; u < kWidth; ++u) {
            add_point(cloud,
                      {0.03f * static_cast<float>(u - kWidth / 2), 1.65f,
                       3.0f + 0.1f * static_cast<float>(v)},
                      0);
        }
    }
    add_car(cloud, -2.0f, 12.0f);
    ExtractOptions o = options_with_bundled_config("instances");
    REQUIRE(o.classes.find("road").column_step == 4);
    const auto stepped = extract_entities(cloud, test_palette(), StereoCamera{}, o);
    for (auto& c : o.classes.classes) {
        if (c.name == "road") c.column_step = 1;
    }
    const auto every = extract_entities(cloud, test_palette(), StereoCamera{}, o);
    REQUIRE(count_class(stepped, "road") == 1);
    REQUIRE(count_class(every, "road") == 1);
    REQUIRE(count_class(stepped, "car") == 1);
    const auto find = [](const scene_schema::EntityDocument& doc, const std::string& name) {
        for (const auto& e : doc.entities) {
            if (e.class_name == name) return e;
        }
        return scene_schema::Entity{};
    };
    const auto a = find(stepped, "road"), b = find(every, "road");
    CHECK(b.point_count == kWidth * kHeight);
    CHECK(a.point_count == kWidth * kHeight);  // 100 columns taken, each standing for 4
    CHECK(std::abs(a.x - b.x) < 0.05);
    CHECK(std::abs(a.z - b.z) < 0.05);
    CHECK(std::abs(a.L - b.L) < 0.1);
    CHECK(std::abs(a.W - b.W) < 0.1);
    // The car is a thing: all its points, the same box.
    const auto car_a = find(stepped, "car"), car_b = find(every, "car");
    CHECK(car_a.point_count == car_b.point_count);
    CHECK(std::abs(car_a.x - car_b.x) < 1e-6);
    CHECK(std::abs(car_a.z - car_b.z) < 1e-6);
    CHECK(std::abs(car_a.theta - car_b.theta) < 1e-9);
}

TEST_CASE("column_step must be 1, 2, 4 or 8, and 1 for a thing", "[entities]") {
    CHECK_THROWS_WITH(
        parse_class_config(R"({"classes": [{"name": "road", "column_step": 3}]})", "x"),
        Catch::Contains("column_step: must be 1, 2, 4 or 8"));
    CHECK_THROWS_WITH(
        parse_class_config(R"({"classes": [{"name": "car", "thing": true, "column_step": 4}]})",
                           "x"),
        Catch::Contains("column_step: must be 1 for a thing"));
}

TEST_CASE("a thing a few pixels wide in the image is a strip of label bleed and is dropped",
          "[extract][suppression]") {
    using namespace cloud_analysis::instances;
    PixelGrid grid;
    grid.width_px = 100;
    grid.height_px = 80;
    std::vector<std::uint32_t> pixels;
    Candidate strip, car;
    // A 3 px wide, 40 px tall strip and a 30 x 20 px block.
    for (std::uint32_t v = 10; v < 50; ++v) {
        for (std::uint32_t u = 5; u < 8; ++u) {
            strip.members.push_back(pixels.size());
            pixels.push_back(v * 100 + u);
        }
    }
    for (std::uint32_t v = 40; v < 60; ++v) {
        for (std::uint32_t u = 50; u < 80; ++u) {
            car.members.push_back(pixels.size());
            pixels.push_back(v * 100 + u);
        }
    }
    CHECK(median_row_width_px(strip.members, pixels, grid) == 3.0);
    CHECK(median_row_width_px(car.members, pixels, grid) == 30.0);
    const auto kept = drop_strips({strip, car}, pixels, grid, 8.0);
    REQUIRE(kept.size() == 1);
    CHECK(kept[0].members.size() == 600);
    CHECK(drop_strips({strip, car}, pixels, grid, 0.0).size() == 2);
}

TEST_CASE("a strip along a larger car at another range is dropped, a narrow car on its own kept",
          "[extract][suppression]") {
    using namespace cloud_analysis::instances;
    PixelGrid grid;
    grid.width_px = 100;
    grid.height_px = 80;
    std::vector<std::uint32_t> pixels;
    Candidate strip, car, far_car;
    const auto add = [&](Candidate& c, std::uint32_t u0, std::uint32_t u1, std::uint32_t v0,
                         std::uint32_t v1) {
        for (std::uint32_t v = v0; v < v1; ++v) {
            for (std::uint32_t u = u0; u < u1; ++u) {
                c.members.push_back(pixels.size());
                pixels.push_back(v * 100 + u);
            }
        }
    };
    // A 30 x 20 px car at 18 m; a 4 px strip right of it at 15 m (a pole's smear over its
    // end); a 5 px wide car at 35 m far left in the image, beside nothing.
    add(car, 40, 70, 40, 60);
    car.range_m = 18.0;
    car.group = 1;
    add(strip, 71, 75, 38, 58);
    strip.range_m = 15.0;
    strip.group = 2;
    add(far_car, 5, 10, 30, 34);
    far_car.range_m = 35.0;
    far_car.group = 3;
    const auto kept = drop_strips_beside({strip, car, far_car}, pixels, grid, 8.0, 10, 1.0);
    REQUIRE(kept.size() == 2);
    CHECK(kept[0].members.size() == car.members.size());
    CHECK(kept[1].members.size() == far_car.members.size());
    // At the car's range it is part of the car's surface, not another object's depth.
    strip.range_m = 18.5;
    CHECK(drop_strips_beside({strip, car, far_car}, pixels, grid, 8.0, 10, 1.0).size() == 3);
    strip.range_m = 15.0;
    CHECK(drop_strips_beside({strip, car, far_car}, pixels, grid, 0.0, 10, 1.0).size() == 3);
    // A piece of the car's own row (its group) is a thing of the row, however narrow.
    strip.group = car.group;
    CHECK(drop_strips_beside({strip, car, far_car}, pixels, grid, 8.0, 10, 1.0).size() == 3);
}

TEST_CASE("a van behind a low car, joined to it by smear, is a car entity of its own",
          "[entities][split]") {
    LabeledCloud cloud;
    add_road(cloud);
    // A 1.2 m high car 10 m ahead (rear and right side) and a 2 m high van 7 m behind it,
    // straight ahead: only the van's top, above the car's roof line, is seen. A trail of
    // wrong matches along the ray joins them into one cluster, and the van lies farther
    // behind the car's nearest points than a car is long: the smear filter drops it.
    for (float y = 0.45f; y <= 1.65f; y += 0.02f) {
        for (float x = -0.9f; x <= 0.9f; x += 0.02f) add_point(cloud, {x, y, 10.0f}, 2);
        for (float z = 10.0f; z <= 14.2f; z += 0.05f) add_point(cloud, {0.9f, y, z}, 2);
    }
    for (float y = -0.35f; y <= 0.45f * 1.7f; y += 0.02f) {
        for (float x = -0.9f; x <= 0.9f; x += 0.02f) add_point(cloud, {x, y, 17.0f}, 2);
    }
    for (float z = 10.2f; z < 17.0f; z += 0.3f) add_point(cloud, {0.0f, 0.6f, z}, 2);
    project_pixels(cloud);
    std::vector<double> centres;
    for (const auto& e : extract_entities(cloud, test_palette(), StereoCamera{},
                                          options_with_bundled_config("instances"))
                             .entities) {
        if (e.class_name == "car") centres.push_back(e.z);
    }
    std::sort(centres.begin(), centres.end());
    REQUIRE(centres.size() == 2);
    CHECK(centres[0] == Approx(12.1).margin(0.3));
    CHECK(centres[1] > 17.0);
}

TEST_CASE("a car passing a parked one 0.3 m beside it is cut from it at the gap",
          "[entities][split]") {
    LabeledCloud cloud;
    add_road(cloud);
    // Parked at x = -4.0 (right side and the right part of its rear seen), the passing car at
    // x = -1.9 (rear and right side): 0.3 m between the parked car's right side and the
    // passing car's left edge, one blob for the clustering, 2.8 m wide across the common
    // heading: more than one car, less than the two widths at which a blob is cut evenly.
    // Points as a camera samples them: the rears, seen square-on, densely (3 cm), the sides,
    // at a grazing angle, sparsely (15 cm).
    const auto rear_and_right_side = [&](float x, float z_rear, float rear_from) {
        for (float y = 0.15f; y <= 1.65f; y += 0.05f) {
            for (float a = rear_from; a <= 0.9f; a += 0.03f)
                add_point(cloud, {x + a, y, z_rear}, 2);
            for (float z = z_rear; z <= z_rear + 4.2f; z += 0.15f)
                add_point(cloud, {x + 0.9f, y, z}, 2);
        }
    };
    rear_and_right_side(-4.0f, 10.9f, 0.2f);
    rear_and_right_side(-1.9f, 12.5f, -0.9f);
    project_pixels(cloud);
    std::vector<scene_schema::Entity> cars;
    for (const auto& e : extract_entities(cloud, test_palette(), StereoCamera{},
                                          options_with_bundled_config("instances"))
                             .entities) {
        if (e.class_name == "car") cars.push_back(e);
    }
    std::sort(cars.begin(), cars.end(), [](const auto& a, const auto& b) { return a.x < b.x; });
    REQUIRE(cars.size() == 2);
    const double x_true[] = {-4.0, -1.9}, z_true[] = {13.0, 14.6};
    for (std::size_t k = 0; k < 2; ++k) {
        CHECK(std::abs(std::cos(cars[k].theta)) < std::sin(10.0 * kPi / 180.0));  // along z
        CHECK(cars[k].x == Approx(x_true[k]).margin(0.3));
        CHECK(cars[k].z == Approx(z_true[k]).margin(0.4));
    }
}

TEST_CASE("two cars side by side under a box at an angle are cut across the viewing ray",
          "[entities][split]") {
    // The passing car (x 0.9..2.7, z 12.4..16.6): rear and left side seen. The parked car
    // beside it, 0.6 m to the right (x 3.3..5.1): its left side from z 13.7. The box fitted to
    // the union of a drive's frame lay 30 degrees off both: across it (and along it) the
    // gap is closed, across the viewing ray it is open. Points as a camera samples them: a
    // face seen square-on densely (3 cm), side faces at a grazing angle sparsely (15 cm).
    std::vector<Eigen::Vector3f> pts;
    for (float y = 0.15f; y <= 1.65f; y += 0.05f) {
        for (float x = 0.9f; x <= 2.7f; x += 0.03f) pts.emplace_back(x, y, 12.4f);
        for (float z = 12.4f; z <= 16.6f; z += 0.15f) pts.emplace_back(0.9f, y, z);
        for (float z = 13.7f; z <= 17.9f; z += 0.15f) pts.emplace_back(3.3f, y, z);
    }
    instances::Indices idx(pts.size());
    std::iota(idx.begin(), idx.end(), std::size_t{0});
    OrientedBox box;
    box.centre_m = Eigen::Vector3d(2.6, 0.9, 14.7);
    box.theta = -kPi / 2.0 + kPi / 6.0;
    box.L_m = 4.6;
    box.W_m = 3.4;
    box.H_m = 1.5;
    const auto split = split_with_car_prior(pts, idx, box);
    REQUIRE(split.parts.size() == 2);
    for (const auto& part : split.parts) {
        const bool left = pts[part.front()].x() < 3.0f;
        for (std::size_t i : part) CHECK((pts[i].x() < 3.0f) == left);
    }
}

namespace {

using test_rigs::kitti_rig;

/// The points of `cloud` the left camera of `c` sees and the matcher can match (column at
/// least fx * B / z: the right view holds the match), with their pixels.
LabeledCloud matched_view(const LabeledCloud& cloud, const StereoCamera& c) {
    LabeledCloud out;
    out.width_px = c.width_px;
    out.height_px = c.height_px;
    for (std::size_t i = 0; i < cloud.size(); ++i) {
        const Eigen::Vector3d p = cloud.xyz_m[i].cast<double>();
        const long u = std::lround(c.fx_px * p.x() / p.z() + c.cx_px);
        const long v = std::lround(c.fy_px * p.y() / p.z() + c.cy_px);
        if (u < c.fx_px * c.baseline_m / p.z() || u >= c.width_px || v < 0 || v >= c.height_px) {
            continue;
        }
        add_point(out, cloud.xyz_m[i], cloud.class_index[i]);
        out.pixel.back() = static_cast<std::uint32_t>(v * c.width_px + u);
    }
    return out;
}

/// The road, far sky, and the right sides (x = -3.95, 1.5 m high) of cars parked along z from
/// each z0 to z1: cars beside the left edge of kitti_rig's view.
LabeledCloud left_edge_scene(const std::vector<std::pair<float, float>>& sides) {
    LabeledCloud cloud;
    for (float x = -8.0f; x <= 6.0f; x += 0.25f) {
        for (float z = 3.0f; z <= 40.0f; z += 0.25f) add_point(cloud, {x, 1.65f, z}, 0);
    }
    for (float x = -20.0f; x <= 20.0f; x += 0.5f) add_point(cloud, {x, -10.0f, 50.0f}, 1);
    for (const auto& [z0, z1] : sides) {
        for (float y = 0.15f; y <= 1.65f; y += 0.05f) {
            for (float z = z0; z <= z1; z += 0.05f) add_point(cloud, {-3.95f, y, z}, 2);
        }
    }
    return cloud;
}

std::vector<double> car_centres_z(const scene_schema::EntityDocument& doc) {
    std::vector<double> z;
    for (const auto& e : doc.entities) {
        if (e.class_name == "car") z.push_back(e.z);
    }
    std::sort(z.begin(), z.end());
    return z;
}

}  // namespace

TEST_CASE(
    "a car cut by the left edge of what the matcher sees at its depth is completed "
    "towards the camera",
    "[entities][truncation]") {
    // A car 4.7 m long from z 3.06 to 7.76: its side shows from z 5.2 (the right view holds no
    // match of anything nearer at that column), far from the image's own first columns,
    // which the far sky reaches. Completed from the visible far end, not from the cut.
    const LabeledCloud cloud = matched_view(left_edge_scene({{3.06f, 7.76f}}), kitti_rig());
    const auto with_rig = car_centres_z(extract_entities(cloud, test_palette(), kitti_rig(),
                                                         options_with_bundled_config("instances")));
    REQUIRE(with_rig.size() == 1);
    CHECK(with_rig[0] == Approx(7.76 - 2.1).margin(0.3));
    // Without the rig the cut is taken for the car's near end.
    const auto without = car_centres_z(extract_entities(cloud, test_palette(), StereoCamera{},
                                                        options_with_bundled_config("instances")));
    REQUIRE(without.size() == 1);
    CHECK(without[0] > 7.0);
}

TEST_CASE("a car cut by the matcher's left edge and the next car in its row are two cars",
          "[entities][truncation][split]") {
    // The cut car shows 2.5 m, then a 0.7 m gap bridged by a sparse trail of wrong matches,
    // then 2 m of the next car: 5.3 m in all, too short for a row of two uncut cars but more
    // than the cut car can show.
    LabeledCloud scene = left_edge_scene({{3.06f, 7.76f}, {8.46f, 10.46f}});
    for (float z = 7.8f; z < 8.46f; z += 0.1f) add_point(scene, {-3.95f, 1.0f, z}, 2);
    const LabeledCloud cloud = matched_view(scene, kitti_rig());
    const auto centres = car_centres_z(extract_entities(cloud, test_palette(), kitti_rig(),
                                                        options_with_bundled_config("instances")));
    REQUIRE(centres.size() == 2);
    CHECK(centres[0] == Approx(7.76 - 2.1).margin(0.3));
    CHECK(centres[1] == Approx(8.46 + 2.1).margin(0.3));
}

TEST_CASE("the far end from pixel columns is off at 0 and at least one prior long otherwise",
          "[extract]") {
    ExtractOptions o;
    CHECK(o.far_column_length_fraction == 1.25);
    CHECK_NOTHROW(o.validate());
    o.far_column_length_fraction = 0.0;
    CHECK_NOTHROW(o.validate());
    for (const double bad : {0.5, 3.5, -1.0, std::numeric_limits<double>::quiet_NaN()}) {
        o.far_column_length_fraction = bad;
        CHECK_THROWS_WITH(o.validate(), Catch::Contains("far_column_length_fraction"));
    }
}

TEST_CASE("a van box longer than any van keeps its far end and a van's length",
          "[entities][split]") {
    LabeledCloud cloud = road_cloud();
    // A 2 m tall van heading along z, 20-25.2 m ahead, its side at x = 4.35 and its roof seen,
    // and joined to its near end the front of the vehicle before it (a 1 m high bonnet,
    // 18.6-19.9 m): a row cut at that vehicle's windscreen foot leaves its front to the van.
    for (float z = 18.6f; z <= 25.2f; z += 0.05f) {
        const float top = z < 19.95f ? 1.0f : 2.0f;
        for (float h = 0.3f; h <= top; h += 0.05f) add_point(cloud, {4.35f, 1.65f - h, z}, 2);
        for (float x = 4.4f; x <= 6.2f; x += 0.1f) add_point(cloud, {x, 1.65f - top, z}, 2);
    }
    // The van nearest the camera (the far end of the points, beyond the prior's reach from the
    // near end, may come out as a box of its own).
    const auto nearest_van = [&](const ExtractOptions& o) {
        std::optional<scene_schema::Entity> out;
        for (const auto& e : extract_entities(cloud, test_palette(), StereoCamera{}, o).entities) {
            if (e.class_name != "car" || e.extra.value("subclass", "") != "van") continue;
            if (!out || e.z < out->z) out = e;
        }
        return out;
    };
    ExtractOptions o = options_with_bundled_config("instances");
    o.row_model = "rules";  // the cascade keeps the blob whole (the partition cuts it at a van)
    const auto limited = nearest_van(o);
    REQUIRE(limited);
    CHECK(limited->L == Approx(o.van_prior_L_m).margin(1e-6));
    CHECK(limited->z + limited->L / 2.0 == Approx(25.2).margin(0.15));  // its far end kept
    o.van_max_L_m = 50.0;
    const auto whole = nearest_van(o);
    REQUIRE(whole);
    CHECK(whole->L > 6.0);
    CHECK(whole->z + whole->L / 2.0 == Approx(25.2).margin(0.15));
    o.van_max_L_m = 5.0;  // shorter than a van
    CHECK_THROWS_WITH(o.validate(), Catch::Contains("van_max_L_m"));
}

namespace {

/// The bundled settings with rows of things cut by the partition model.
ExtractOptions partition_options() {
    ExtractOptions o = options_with_bundled_config("instances");
    o.row_model = "partition";
    return o;
}

}  // namespace

TEST_CASE("the row partition cuts a parked row at its clear gaps, one car a piece",
          "[entities][split]") {
    LabeledCloud cloud;
    add_road(cloud);
    const std::vector<float> starts = {8.0f, 12.7f, 17.4f};
    add_row_sides(cloud, starts);
    project_pixels(cloud);
    std::vector<scene_schema::Entity> cars = cars_of(cloud, partition_options());
    REQUIRE(cars.size() == 3);
    std::sort(cars.begin(), cars.end(), [](const auto& a, const auto& b) { return a.z < b.z; });
    for (std::size_t k = 0; k < 3; ++k) {
        CHECK(cars[k].z == Approx(double{starts[k]} + 2.1).margin(0.3));
    }
}

TEST_CASE("the row partition cuts touching cars without gaps or valleys at their lengths",
          "[entities][split]") {
    LabeledCloud cloud;
    add_road(cloud);
    // Three cars bumper to bumper seen side-on as one flat side 12.6 m long: no gap, no valley;
    // three pieces of a car's length are likelier than one, two or four.
    for (float y = 0.15f; y <= 1.65f; y += 0.05f) {
        for (float z = 10.0f; z <= 22.6f; z += 0.05f) add_point(cloud, {-4.0f, y, z}, 2);
    }
    const std::vector<scene_schema::Entity> cars = cars_of(cloud, partition_options());
    REQUIRE(cars.size() == 3);
    for (const auto& c : cars) CHECK(c.L < 5.5);
}

TEST_CASE("the row partition leaves a gap's few high points to no car", "[entities][split]") {
    // As above ("a gap's few high points ..."): two cars end to end 2.4 m apart, 120 points of
    // a crown bled onto the mask high in the gap. The piece holding them is nothing: it holds
    // little surface and no car's length.
    LabeledCloud cloud;
    add_road(cloud);
    const auto add_side = [&](float z0, float z1, float top) {
        for (float y = 0.15f; y <= top + 1e-4f; y += 0.05f) {
            for (float z = z0; z < z1; z += 0.025f) add_point(cloud, {-1.1f, 1.65f - y, z}, 2);
        }
    };
    add_side(10.0f, 13.6f, 1.5f);
    add_side(13.6f, 14.2f, 1.0f);
    for (int k = 0; k < 120; ++k) {
        const auto f = static_cast<float>(k);
        add_point(cloud, {-1.1f, 1.65f - (1.7f + 0.0016f * f), 14.7f + 0.0147f * f}, 2);
    }
    add_side(16.6f, 17.4f, 1.0f);
    add_side(17.4f, 20.8f, 1.5f);
    std::vector<scene_schema::Entity> cars = cars_of(cloud, partition_options());
    REQUIRE(cars.size() == 2);
    std::sort(cars.begin(), cars.end(), [](const auto& a, const auto& b) { return a.z < b.z; });
    CHECK(cars[0].z == Approx(12.1).margin(0.3));
    CHECK(cars[1].z == Approx(18.7).margin(0.3));
}

TEST_CASE("row_model must be rules or partition", "[entities]") {
    ExtractOptions o = options_with_bundled_config("instances");
    o.row_model = "dp";
    CHECK_THROWS_WITH(o.validate(), Catch::Contains("row_model"));
    o.row_model = "partition";
    CHECK_NOTHROW(o.validate());
}

TEST_CASE("the row partition cuts where a row is seen through between two things",
          "[entities][split]") {
    LabeledCloud cloud;
    add_road(cloud);
    // A 3.6 m and a 4.8 m car seen side-on as one flat side 1.5 m tall, and 0.4 m between
    // them where only a few points of the mask lie, as high as the cars (what is behind them,
    // seen between): a gap with neither a valley nor an empty bin. Without it the lengths alone
    // would cut near the middle (4.4 m each).
    for (float y = 0.15f; y <= 1.65f; y += 0.05f) {
        for (float z = 10.0f; z <= 18.8f; z += 0.05f) {
            if (z < 13.6f || z > 14.0f) add_point(cloud, {-4.0f, y, z}, 2);
        }
    }
    for (float y = 0.15f; y <= 1.65f; y += 0.6f) {
        for (float z = 13.65f; z < 14.0f; z += 0.1f) add_point(cloud, {-4.0f, y, z}, 2);
    }
    std::vector<scene_schema::Entity> cars = cars_of(cloud, partition_options());
    REQUIRE(cars.size() == 2);
    std::sort(cars.begin(), cars.end(), [](const auto& a, const auto& b) { return a.z < b.z; });
    // 31 points every 5 cm: 2232 on the first car's side, 2976 on the second's (the box fit
    // leaves out some of its far end).
    CHECK(cars[0].point_count < 2232 + 31);
    CHECK(cars[1].point_count > cars[0].point_count + 400);
}

TEST_CASE("the row partition counts a sparse far car's points past the row's profile",
          "[entities][split]") {
    LabeledCloud cloud;
    add_road(cloud);
    // Two cars seen densely, 0.45 m apart, then 60 points (< 100, the car minimum; >= 50, the
    // minimum of a row's piece) of a third, 1 m of it, past the 99.5 % of the row's points
    // where its profile ends.
    add_sparse_third_car(cloud, 10, 0.15f, 0.15f, 6);
    project_pixels(cloud);
    std::vector<scene_schema::Entity> cars = cars_of(cloud, partition_options());
    REQUIRE(cars.size() == 3);
    std::sort(cars.begin(), cars.end(), [](const auto& a, const auto& b) { return a.z < b.z; });
    CHECK(cars[2].z == Approx(17.3 + 2.1).margin(0.3));
}
