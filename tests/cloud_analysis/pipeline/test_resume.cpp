#include <catch2/catch.hpp>

#include <filesystem>
#include <fstream>
#include <string>

#include <unistd.h>

#include <scene_schema/entities.hpp>

#include "cloud_analysis/cloud/cloud_io.hpp"
#include "cloud_analysis/cloud/semantic.hpp"
#include "cloud_analysis/io/io.hpp"
#include "cloud_analysis/pipeline/resume.hpp"

using namespace cloud_analysis;

namespace {

/// A fresh folder for one test case, removed at the end.
struct TempDir {
    std::filesystem::path path;
    explicit TempDir(const std::string& name)
        : path(std::filesystem::temp_directory_path() /
               ("stereoscene_resume_" + name + "_" + std::to_string(::getpid()))) {
        std::filesystem::remove_all(path);
        std::filesystem::create_directories(path);
    }
    ~TempDir() {
        std::error_code ignored;
        std::filesystem::remove_all(path, ignored);
    }
};

void write(const std::filesystem::path& path, const std::string& bytes) {
    std::ofstream(path, std::ios::binary) << bytes;
}

LabeledCloud cloud_of(std::size_t n, const Palette& palette) {
    LabeledCloud c;
    c.width_px = static_cast<int>(n);
    c.height_px = 1;
    for (std::size_t i = 0; i < n; ++i) {
        c.xyz_m.push_back({0.5f * static_cast<float>(i), -1.0f, 10.0f});
        c.colour.push_back(Rgb{10, 20, 30});
        c.class_index.push_back(find_class(palette, "car"));
        c.pixel.push_back(static_cast<int>(i));
    }
    return c;
}

std::string entity_file(const std::string& frame) {
    scene_schema::EntityDocument doc;
    doc.frame.id = frame;
    return scene_schema::dump_checked(doc);
}

/// Writes every output of `frame` as the batch does.
void write_frame(const std::filesystem::path& dir, const std::string& frame, const Palette& palette,
                 std::size_t points = 5) {
    const LabeledCloud cloud = cloud_of(points, palette);
    write(dir / (frame + ".xyz"), format_xyz(cloud, palette));
    write(dir / (frame + ".pcd"), format_pcd(cloud, palette));
    write(dir / (frame + ".ply"), format_ply(cloud, palette));
    DisparityMap disparity;
    disparity.width_px = 4;
    disparity.height_px = 2;
    disparity.disparity_px.assign(8, 10.0f);
    write(dir / (frame + "_disparity.png"), encode_kitti_disparity_png(disparity));
    write(dir / (frame + ".json"), entity_file(frame));
}

const FrameOutputs kAll{{"xyz", "pcd", "ply"}, true};

}  // namespace

TEST_CASE("a frame with every output whole and valid is done", "[resume]") {
    const Palette city = load_palette("cityscapes");
    TempDir dir("whole");
    write_frame(dir.path, "000007", city);
    CHECK(frame_outputs_problem(dir.path, "000007", kAll) == "");
    CHECK(frame_outputs_problem(dir.path, "000007", FrameOutputs{}) == "");
    CHECK(cloud_file_points(dir.path / "000007.pcd") == 5);
    CHECK(cloud_file_points(dir.path / "000007.ply") == 5);
    CHECK(cloud_file_points(dir.path / "000007.xyz") == 5);
    CHECK(frame_outputs_problem(dir.path, "000008", kAll) != "");
}

TEST_CASE("a frame is not done when any output is missing, cut, padded or invalid", "[resume]") {
    const Palette city = load_palette("cityscapes");
    TempDir dir("broken");
    const std::string frame = "000003";
    const auto problem = [&] { return frame_outputs_problem(dir.path, frame, kAll); };
    const auto cut = [](const std::filesystem::path& p, std::uintmax_t bytes) {
        std::filesystem::resize_file(p, std::filesystem::file_size(p) - bytes);
    };
    SECTION("no entity file (the writer was killed before it)") {
        write_frame(dir.path, frame, city);
        std::filesystem::remove(dir.path / (frame + ".json"));
        CHECK_THAT(problem(), Catch::Contains("000003.json: missing"));
    }
    SECTION("an entity file that breaks the schema") {
        write_frame(dir.path, frame, city);
        write(dir.path / (frame + ".json"), R"({"schema_version": "1.0", "entities": 3})");
        CHECK_THAT(problem(), Catch::Contains("000003.json"));
    }
    SECTION("an entity file of another frame") {
        write_frame(dir.path, frame, city);
        write(dir.path / (frame + ".json"), entity_file("000004"));
        CHECK_THAT(problem(), Catch::Contains("names frame '000004'"));
    }
    SECTION("a truncated PCD, PLY or xyz, or one byte too many") {
        for (const char* ext : {".pcd", ".ply", ".xyz"}) {
            write_frame(dir.path, frame, city);
            cut(dir.path / (frame + ext), 3);
            CAPTURE(ext);
            CHECK_THAT(problem(), Catch::Contains(frame + ext));
        }
        write_frame(dir.path, frame, city);
        std::ofstream(dir.path / (frame + ".ply"), std::ios::app) << "x";
        CHECK_THAT(problem(), Catch::Contains(".ply"));
    }
    SECTION("clouds that disagree on the number of points") {
        write_frame(dir.path, frame, city);
        const LabeledCloud other = cloud_of(6, city);
        write(dir.path / (frame + ".ply"), format_ply(other, city));
        CHECK_THAT(problem(), Catch::Contains("6 points"));
    }
    SECTION("a missing cloud or a cut disparity PNG") {
        write_frame(dir.path, frame, city);
        std::filesystem::remove(dir.path / (frame + ".xyz"));
        CHECK_THAT(problem(), Catch::Contains(".xyz: missing"));
        write_frame(dir.path, frame, city);
        cut(dir.path / (frame + "_disparity.png"), 1);
        CHECK_THAT(problem(), Catch::Contains("not a complete PNG"));
    }
}

TEST_CASE("outputs are listed in writing order, the entity file last", "[resume]") {
    const auto paths = frame_output_paths("out", "f", kAll);
    REQUIRE(paths.size() == 5);
    CHECK(paths.front() == std::filesystem::path("out/f_disparity.png"));
    CHECK(paths.back() == std::filesystem::path("out/f.json"));
}

TEST_CASE("stale temporaries of the share's frames are removed, others' kept", "[resume]") {
    TempDir dir("stale");
    write(dir.path / ".000001.json.tmp-Ab12Cd", "{");
    write(dir.path / ".000001.pcd.tmp-xYz123", "");
    write(dir.path / ".000002.json.tmp-Ab12Cd", "{");  // another shard's frame, in flight
    write(dir.path / "000001.json", "{}");
    CHECK(remove_stale_temporaries(dir.path, {"000001"}, FrameOutputs{{"pcd"}, false}) == 2);
    CHECK_FALSE(std::filesystem::exists(dir.path / ".000001.json.tmp-Ab12Cd"));
    CHECK_FALSE(std::filesystem::exists(dir.path / ".000001.pcd.tmp-xYz123"));
    CHECK(std::filesystem::exists(dir.path / ".000002.json.tmp-Ab12Cd"));
    CHECK(std::filesystem::exists(dir.path / "000001.json"));
}
