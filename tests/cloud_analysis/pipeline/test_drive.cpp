#include <catch2/catch.hpp>

#include <filesystem>
#include <fstream>
#include <string>

#include "cloud_analysis/pipeline/drive.hpp"

using namespace cloud_analysis;
namespace fs = std::filesystem;

namespace {

void touch(const fs::path& p, const std::string& text = "x") {
    fs::create_directories(p.parent_path());
    std::ofstream(p) << text;
}

/// A KITTI raw date folder with one drive of `n` frames (empty files: only paths are read).
fs::path raw_drive(const std::string& name, int n, const std::string& timestamps) {
    const fs::path date = fs::temp_directory_path() / ("stereoscene_drive_" + name) / "2011_09_26";
    fs::remove_all(date.parent_path());
    const fs::path drive = date / "2011_09_26_drive_0001_sync";
    for (int i = 0; i < n; ++i) {
        char stem[16];
        std::snprintf(stem, sizeof stem, "%010d", i);
        touch(drive / "image_02" / "data" / (std::string(stem) + ".png"));
        touch(drive / "image_03" / "data" / (std::string(stem) + ".png"));
    }
    touch(date / "calib_cam_to_cam.txt");
    if (!timestamps.empty()) touch(drive / "image_02" / "timestamps.txt", timestamps);
    return drive;
}

}  // namespace

TEST_CASE("KITTI raw timestamps become Unix seconds", "[drive]") {
    CHECK(*parse_kitti_timestamp("1970-01-02 00:00:01.5") == Approx(86401.5));
    CHECK(*parse_kitti_timestamp("2011-09-26 13:02:25.964389445") ==
          Approx(1317042145.9643896).epsilon(1e-12));
    CHECK(*parse_kitti_timestamp("2000-03-01 00:00:00.000000000") == Approx(951868800.0));
    CHECK_FALSE(parse_kitti_timestamp("2011-09-26"));
    CHECK_FALSE(parse_kitti_timestamp("2011-13-26 13:02:25.9"));
    CHECK_FALSE(parse_kitti_timestamp("2011-09-26 13:02:25.9 extra"));
}

TEST_CASE("a KITTI raw drive lists its frames in order with the date folder's calibration",
          "[drive]") {
    const fs::path drive = raw_drive("ok", 3,
                                     "2011-09-26 13:02:25.0\n2011-09-26 13:02:25.1\n"
                                     "2011-09-26 13:02:25.2\n");
    const auto frames = kitti_raw_drive(drive, {}, {});
    REQUIRE(frames.size() == 3);
    CHECK(frames[1].id == "0000000001");
    CHECK(frames[1].paths.frame_id == "0000000001");
    CHECK(frames[1].paths.right == drive / "image_03" / "data" / "0000000001.png");
    CHECK(frames[1].paths.calibration.filename() == "calib_cam_to_cam.txt");
    CHECK(frames[1].paths.semantic.empty());
    REQUIRE(frames[2].timestamp_s);
    CHECK(*frames[2].timestamp_s - *frames[0].timestamp_s == Approx(0.2));
    // A calibration given wins; no timestamps file, no times.
    fs::remove(drive / "image_02" / "timestamps.txt");
    const auto given = kitti_raw_drive(drive, "/elsewhere/calib.txt", {});
    CHECK(given[0].paths.calibration == "/elsewhere/calib.txt");
    CHECK_FALSE(given[0].timestamp_s);
}

TEST_CASE("a KITTI raw drive with a missing image, semantic image or time is refused", "[drive]") {
    const fs::path drive = raw_drive("bad", 2, "2011-09-26 13:02:25.0\n");
    CHECK_THROWS_WITH(kitti_raw_drive(drive, {}, {}), Catch::Contains("1 lines for 2 frames"));
    fs::remove(drive / "image_02" / "timestamps.txt");
    CHECK_THROWS_WITH(kitti_raw_drive(drive, {}, drive / "semantic"),
                      Catch::Contains("no semantic image for frame 0000000000"));
    fs::remove(drive / "image_03" / "data" / "0000000001.png");
    CHECK_THROWS_WITH(kitti_raw_drive(drive, {}, {}),
                      Catch::Contains("no right image for frame 0000000001"));
    CHECK_THROWS_WITH(kitti_raw_drive(drive / "image_02", {}, {}),
                      Catch::Contains("not a KITTI raw drive"));
}

TEST_CASE("a list of pairs gives frames named by their left images", "[drive]") {
    const auto frames =
        pair_list("# left right semantic\nl/a.png r/a.png\n\nl/b.png r/b.png s/b.png # c\n",
                  "/data", "/data/calib.yaml", "pairs.txt");
    REQUIRE(frames.size() == 2);
    CHECK(frames[0].id == "a");
    CHECK(frames[0].paths.left == fs::path("/data/l/a.png"));
    CHECK(frames[0].paths.semantic.empty());
    CHECK(frames[1].paths.semantic == fs::path("/data/s/b.png"));
    CHECK(frames[1].paths.calibration == fs::path("/data/calib.yaml"));
    CHECK_THROWS_WITH(pair_list("l/a.png\n", "", "c", "pairs.txt"),
                      Catch::Contains("pairs.txt, line 1") && Catch::Contains("got 1 paths"));
    CHECK_THROWS_WITH(pair_list("x/a.png r/1.png\ny/a.png r/2.png\n", "", "c", "pairs.txt"),
                      Catch::Contains("second frame named 'a'") && Catch::Contains("line 2"));
    CHECK_THROWS_WITH(pair_list("# nothing\n", "", "c", "pairs.txt"), Catch::Contains("no frames"));
}
