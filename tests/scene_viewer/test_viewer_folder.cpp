#include <catch2/catch.hpp>

#include <algorithm>
#include <array>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <set>
#include <string>

#include <nlohmann/json.hpp>
#include <scene_viewer/ecs/coordinates.hpp>
#include <scene_viewer/views/trails.hpp>
#include <scene_viewer/views/views.hpp>
#include <scene_viewer/web/viewer_folder.hpp>

using namespace scene_viewer;

namespace {

std::string b64(const std::string& text) {
    return base64_encode(reinterpret_cast<const unsigned char*>(text.data()), text.size());
}

/// The JSON and BIN chunks of a .glb (glTF 2.0 binary container).
struct Glb {
    nlohmann::json json;
    std::string bin;
};

Glb split_glb(const std::vector<unsigned char>& bytes) {
    REQUIRE(bytes.size() >= 20);
    REQUIRE(std::string(bytes.begin(), bytes.begin() + 4) == "glTF");
    auto u32 = [&](std::size_t at) {
        std::uint32_t v;
        std::memcpy(&v, bytes.data() + at, 4);
        return v;
    };
    const std::uint32_t json_length = u32(12);
    Glb glb;
    glb.json = nlohmann::json::parse(bytes.begin() + 20, bytes.begin() + 20 + json_length);
    const std::size_t bin_at = 20 + json_length;
    if (bin_at + 8 <= bytes.size()) {
        const std::uint32_t bin_length = u32(bin_at);
        glb.bin.assign(bytes.begin() + static_cast<long>(bin_at) + 8,
                       bytes.begin() + static_cast<long>(bin_at + 8 + bin_length));
    }
    return glb;
}

PointCloud two_class_cloud() {
    PointCloud cloud;
    cloud.positions_kitti = {{1.0f, 0.5f, 10.0f}, {0.0f, 1.6f, 8.0f}, {1.2f, 0.6f, 10.5f}};
    cloud.colours = {{{0, 0, 142}}, {{128, 64, 128}}, {{0, 0, 142}}};
    cloud.class_ids = {26, 7, 26};
    return cloud;
}

scene_schema::EntityDocument one_car() {
    scene_schema::EntityDocument doc;
    scene_schema::CameraIntrinsics k;
    k.width_px = 640;
    k.height_px = 200;
    k.fx_px = k.fy_px = 500.0;
    k.cx_px = 320.0;
    k.cy_px = 90.0;
    doc.frame.camera = k;
    scene_schema::Entity car;
    car.id = "car-1";
    car.class_name = "car";
    car.class_id = 26;
    car.x = 1.0;
    car.y = 0.9;
    car.z = 12.0;
    car.W = 1.8;
    car.H = 1.5;
    car.L = 4.2;
    doc.entities.push_back(car);
    return doc;
}

}  // namespace

TEST_CASE("base64 encodes the RFC 4648 test vectors", "[web]") {
    CHECK(b64("") == "");
    CHECK(b64("f") == "Zg==");
    CHECK(b64("fo") == "Zm8=");
    CHECK(b64("foo") == "Zm9v");
    CHECK(b64("foob") == "Zm9vYg==");
    CHECK(b64("fooba") == "Zm9vYmE=");
    CHECK(b64("foobar") == "Zm9vYmFy");
    const unsigned char high[] = {0xff, 0xfe, 0xfd};
    CHECK(base64_encode(high, 3) == "//79");
}

TEST_CASE("a cloud becomes one glTF POINTS mesh per class in the glTF frame", "[web]") {
    const PointCloud cloud = two_class_cloud();
    const Glb glb = split_glb(point_cloud_glb_bytes(cloud));
    const auto& nodes = glb.json.at("nodes");
    REQUIRE(nodes.size() == 2);
    CHECK(nodes[0].at("name") == "cloud_class_7");  // classes in id order
    CHECK(nodes[1].at("name") == "cloud_class_26");
    CHECK(nodes[1].at("extras").at("class_id") == 26);
    const auto& car = glb.json.at("meshes")[1].at("primitives")[0];
    CHECK(car.at("mode") == 0);  // POINTS
    const auto& accessors = glb.json.at("accessors");
    const auto& position = accessors[car.at("attributes").at("POSITION").get<std::size_t>()];
    REQUIRE(position.at("count") == 2);
    const auto& view = glb.json.at("bufferViews")[position.at("bufferView").get<std::size_t>()];
    const auto offset = view.find("byteOffset");
    const std::size_t at = offset == view.end() ? 0 : offset->get<std::size_t>();
    glm::vec3 got[2];
    std::memcpy(got, glb.bin.data() + at, sizeof got);
    // The class's points, in a shuffled order.
    const glm::vec3 a = kitti_to_gl(cloud.positions_kitti[0]);
    const glm::vec3 b = kitti_to_gl(cloud.positions_kitti[2]);
    CHECK(((got[0] == a && got[1] == b) || (got[0] == b && got[1] == a)));
    const auto& colour = accessors[car.at("attributes").at("COLOR_0").get<std::size_t>()];
    CHECK(colour.at("normalized") == true);
    CHECK(colour.at("componentType") == 5121);  // unsigned byte
}

TEST_CASE("a cloud's points are shuffled the same way every time", "[web]") {
    PointCloud cloud;
    for (int i = 0; i < 1000; ++i) cloud.positions_kitti.emplace_back(float(i), 0.0f, 10.0f);
    const std::vector<unsigned char> first = point_cloud_glb_bytes(cloud);
    CHECK(first == point_cloud_glb_bytes(cloud));
    const Glb glb = split_glb(first);
    const auto& view = glb.json.at("bufferViews")[0];
    const auto offset = view.find("byteOffset");
    const std::size_t at = offset == view.end() ? 0 : offset->get<std::size_t>();
    std::vector<glm::vec3> got(1000);
    std::memcpy(got.data(), glb.bin.data() + at, got.size() * sizeof(glm::vec3));
    // The first tenth is a sample of the whole range, not its first tenth.
    float first_tenth_max = 0.0f;
    for (int i = 0; i < 100; ++i) first_tenth_max = std::max(first_tenth_max, got[i].x);
    CHECK(first_tenth_max > 800.0f);
}

TEST_CASE("a cloud with mismatched colours is refused", "[web]") {
    PointCloud cloud = two_class_cloud();
    cloud.colours.pop_back();
    CHECK_THROWS_AS(point_cloud_glb_bytes(cloud), std::invalid_argument);
}

TEST_CASE("the viewer folder carries the page, the data and the views of views.cpp", "[web]") {
    ViewerScene scene;
    scene.layers.push_back({"truth", one_car()});
    scene.layers.push_back({"analysis", one_car()});
    scene.scene_glb = {'g', 'l', 'T', 'F'};
    const PointCloud cloud = two_class_cloud();
    scene.cloud = &cloud;
    ViewerAssets assets{"three", "<title>{{TITLE}}</title>{{DATA_SCRIPTS}}", "css", {}};
    for (const char* name : kViewerScripts) assets.scripts[name] = "script";
    ViewerOptions options;
    options.title = "a<b";
    const auto files = viewer_files(scene, assets, options);
    for (const char* name :
         {"index.html", "three.min.js", "viewer.js", "viewer_util.js", "viewer_models.js",
          "viewer_panel.js", "viewer_drive.js", "viewer.css", "scene.glb", "cloud.glb",
          "data/scene-data.js", "data/scene-glb.js", "data/cloud-glb.js"}) {
        INFO(name);
        CHECK(files.count(name) == 1);
    }
    const std::string& html = files.at("index.html");
    CHECK(html.find("<title>a&lt;b</title>") == 0);
    CHECK(html.find("<script id=\"cloud-data\" src=\"data/cloud-glb.js\" defer></script>") !=
          std::string::npos);
    CHECK(files.at("data/scene-glb.js").find("\"scene.glb\"] = \"Z2xURg==\";") !=
          std::string::npos);

    const std::string& script = files.at("data/scene-data.js");
    const std::string prefix = "window.SCENE_VIEWER_DATA = ";
    REQUIRE(script.rfind(prefix, 0) == 0);
    const auto data =
        nlohmann::json::parse(script.substr(prefix.size(), script.size() - prefix.size() - 2));
    CHECK(data.at("layers").size() == 2);
    CHECK(data.at("layers")[1].at("label") == "analysis");
    CHECK(data.at("layers")[0].at("colour") != data.at("layers")[1].at("colour"));
    CHECK(data.at("layers")[0].at("entities")[0].at("id") == "car-1");
    CHECK(data.at("views").at("camera").at("fx") == 500.0);
    CHECK(data.at("views").at("camera").at("cy") == 90.0);
    const glm::vec3 eye = kitti_to_gl(chase_view().eye_kitti);
    CHECK(data.at("views").at("chase").at("eye")[1].get<float>() == eye.y);
    CHECK(data.at("cloud").at("points") == 3);
}

TEST_CASE("a viewer without entity files or with a bad point size is refused", "[web]") {
    const ViewerAssets assets;
    ViewerScene scene;
    CHECK_THROWS_AS(viewer_files(scene, assets, ViewerOptions{}), std::invalid_argument);
    scene.layers.push_back({"one", one_car()});
    ViewerOptions options;
    options.point_size_px = 0.0f;
    CHECK_THROWS_AS(viewer_files(scene, assets, options), std::invalid_argument);
}

namespace {

/// A two-frame drive: a car (track 3) moving 1 m forward, a road patch, a left image per frame.
ViewerDrive two_frame_drive() {
    ViewerDrive drive;
    drive.id = "drive";
    drive.fps = 5.0;
    drive.trail_frames = 4;
    for (int i = 0; i < 2; ++i) {
        ViewerDriveFrame f;
        f.index = 10 + 2 * i;  // a missing frame between them
        f.name = "f" + std::to_string(i);
        f.document = one_car();
        f.document.entities[0].track_id = 3;
        f.document.entities[0].z += i;
        scene_schema::Entity road;
        road.id = "road-1";
        road.class_name = "road";
        road.class_id = 7;
        road.y = 1.6;
        road.W = 8.0;
        road.H = 0.2;
        road.L = 30.0;
        f.document.entities.push_back(road);
        f.background_bytes = std::string("\x89PNG\r\n\x1a\n", 8) + "pixels";
        drive.frames.push_back(std::move(f));
    }
    drive.frames[1].timestamp_s = 2.5;
    drive.models_glb = {'g', 'l', 'T', 'F'};
    return drive;
}

}  // namespace

TEST_CASE("a drive's frames are scripts of their own, with trails and extent in the data",
          "[web]") {
    const ViewerDrive drive = two_frame_drive();
    ViewerScene scene;
    scene.layers.push_back({"drive", drive.frames[0].document});
    scene.scene_glb = {'g', 'l', 'T', 'F'};
    scene.drive = &drive;
    ViewerAssets assets{"three", "{{DATA_SCRIPTS}}", "css", {}};
    const auto files = viewer_files(scene, assets, ViewerOptions{});
    for (const char* name : {"frames/000000.js", "frames/000001.js", "frames/000000.png",
                             "frames/000001.png", "models.glb", "data/models-glb.js"}) {
        INFO(name);
        CHECK(files.count(name) == 1);
    }
    CHECK(files.at("index.html").find("data/models-glb.js") != std::string::npos);
    CHECK(files.at("data/models-glb.js").find("\"models.glb\"] = \"Z2xURg==\";") !=
          std::string::npos);
    const std::string& frame = files.at("frames/000001.js");
    const std::string call = "window.SceneViewerFrames.add(";
    REQUIRE(frame.rfind(call, 0) == 0);
    const auto payload =
        nlohmann::json::parse(frame.substr(call.size(), frame.size() - call.size() - 3));
    CHECK(payload.at("position") == 1);
    CHECK(payload.at("entities").size() == 2);
    CHECK(payload.at("entities")[0].at("track_id") == 3);

    const std::string& script = files.at("data/scene-data.js");
    const auto data = nlohmann::json::parse(
        script.substr(script.find('{'), script.rfind('}') - script.find('{') + 1));
    const auto& d = data.at("drive");
    CHECK(d.at("fps") == 5.0);
    CHECK(d.at("trail_frames") == 4);
    REQUIRE(d.at("frames").size() == 2);
    CHECK(d.at("frames")[0].at("time") == Approx(2.0));  // index 10 at 5 Hz, no timestamp
    CHECK(d.at("frames")[1].at("time") == Approx(2.5));  // the timestamp wins
    CHECK(d.at("frames")[1].at("image") == "frames/000001.png");
    CHECK(d.at("frames")[1].at("script") == "frames/000001.js");
    // One track, its ground contact per frame: the box bottom y + H / 2.
    REQUIRE(d.at("tracks").size() == 1);
    const auto& points = d.at("tracks")[0].at("points");
    REQUIRE(points.size() == 2);
    const auto& car = drive.frames[1].document.entities[0];
    CHECK(points[1][0] == 1);
    CHECK(points[1][1] == Approx(car.x));
    CHECK(points[1][2] == Approx(car.y + 0.5 * car.H));
    CHECK(points[1][3] == Approx(car.z));
    // The extent holds every footprint of every frame (the road's 30 m length included).
    CHECK(d.at("extent")[3].get<double>() >= 15.0);
    // The classes of every frame reach the page.
    std::set<std::string> names;
    for (const auto& c : data.at("classes")) names.insert(c.at("name").get<std::string>());
    CHECK(names == std::set<std::string>{"car", "road"});
}

TEST_CASE("a drive with poses gives its trails in the world, each frame's camera and its path",
          "[web]") {
    ViewerDrive drive = two_frame_drive();
    // The camera drives 2 m forward between the frames; the car stays where it was.
    drive.frames[0].document.frame.pose =
        std::array<double, 12>{1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0};
    drive.frames[1].document.frame.pose =
        std::array<double, 12>{1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 2};
    drive.frames[1].document.entities[0].z = drive.frames[0].document.entities[0].z - 2.0;
    ViewerScene scene;
    scene.layers.push_back({"drive", drive.frames[0].document});
    scene.scene_glb = {'g', 'l', 'T', 'F'};
    scene.drive = &drive;
    ViewerAssets assets{"three", "{{DATA_SCRIPTS}}", "css", {}};
    const std::string script =
        viewer_files(scene, assets, ViewerOptions{}).at("data/scene-data.js");
    const auto d = nlohmann::json::parse(
                       script.substr(script.find('{'), script.rfind('}') - script.find('{') + 1))
                       .at("drive");
    CHECK(d.at("world") == true);
    // Column-major camera_from_world: the second camera sees the world 2 m nearer.
    CHECK(d.at("frames")[1].at("camera_from_world")[14] == Approx(-2.0));
    CHECK(d.at("frames")[0].at("camera_from_world")[14] == Approx(0.0));
    REQUIRE(d.at("tracks").size() == 2);
    for (const auto& track : d.at("tracks")) {
        const auto& points = track.at("points");
        REQUIRE(points.size() == 2);
        if (track.at("class") == kEgoClassName) {
            // The ground under the camera, 1.65 m below it, 2 m on in the world.
            CHECK(points[1][2] == Approx(kEgoGroundBelow_m));
            CHECK(points[1][3] == Approx(2.0));
        } else {
            // A car that did not move: one place in the world in both frames.
            CHECK(points[1][3] == Approx(points[0][3].get<double>()));
        }
    }
    // Without a pose on every frame the trails stay in each frame's camera.
    drive.frames[1].document.frame.pose.reset();
    const std::string still = viewer_files(scene, assets, ViewerOptions{}).at("data/scene-data.js");
    CHECK(
        nlohmann::json::parse(still.substr(still.find('{'), still.rfind('}') - still.find('{') + 1))
            .at("drive")
            .at("world") == false);
}

TEST_CASE("class templates leave ground out and place the unit box without rotation", "[web]") {
    const auto doc = class_template_document({{"car", 26}, {"road", 7}, {"person", 24}});
    REQUIRE(doc.entities.size() == 2);
    for (const auto& e : doc.entities) {
        CHECK(e.id == kClassTemplatePrefix + e.class_name);
        CHECK(e.W == 1.0);
        CHECK(e.H == 1.0);
        CHECK(e.L == 1.0);
        // The page places an entity with rotation pi/2 - theta about +y, as box_world_matrix
        // does: a template's placement is the identity, its node matrix the model's fit alone.
        const glm::mat4 m = box_world_matrix({0.0f, 0.0f, 0.0f}, e.theta, {1.0f, 1.0f, 1.0f});
        for (int c = 0; c < 4; ++c) {
            for (int r = 0; r < 4; ++r) CHECK(m[c][r] == Approx(c == r ? 1.0 : 0.0).margin(1e-6));
        }
    }
}

TEST_CASE("a drive beside a cloud, or an image that is not PNG or JPEG, is refused", "[web]") {
    ViewerDrive drive = two_frame_drive();
    ViewerScene scene;
    scene.layers.push_back({"drive", drive.frames[0].document});
    scene.drive = &drive;
    const PointCloud cloud = two_class_cloud();
    scene.cloud = &cloud;
    const ViewerAssets assets;
    CHECK_THROWS_AS(viewer_files(scene, assets, ViewerOptions{}), std::invalid_argument);
    scene.cloud = nullptr;
    drive.frames[1].background_bytes = "GIF89a";
    CHECK_THROWS_WITH(viewer_files(scene, assets, ViewerOptions{}),
                      Catch::Contains("frame f1") && Catch::Contains("neither PNG nor JPEG"));
    drive.frames.clear();
    CHECK_THROWS_AS(viewer_files(scene, assets, ViewerOptions{}), std::invalid_argument);
}
