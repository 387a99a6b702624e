#include <cstdint>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <string>

#include <catch2/catch.hpp>

#include "scene_viewer/assets/point_cloud.hpp"

using namespace scene_viewer;
namespace fs = std::filesystem;

namespace {

fs::path temp_file(const std::string& name, const std::string& bytes) {
    const fs::path dir = fs::temp_directory_path() / "scene_viewer_tests";
    fs::create_directories(dir);
    const fs::path path = dir / name;
    std::ofstream(path, std::ios::binary) << bytes;
    return path;
}

template <class T>
void put(std::string& s, T v) {
    char b[sizeof(T)];
    std::memcpy(b, &v, sizeof(T));
    s.append(b, sizeof(T));
}

}  // namespace

TEST_CASE("A binary PLY as cloud-analysis writes it reads back positions, colours and classes",
          "[cloud]") {
    std::string s =
        "ply\nformat binary_little_endian 1.0\nelement vertex 2\nproperty float x\n"
        "property float y\nproperty float z\nproperty uchar red\nproperty uchar green\n"
        "property uchar blue\nproperty int scalar_class\nend_header\n";
    put(s, 1.5f), put(s, -0.25f), put(s, 10.0f), put<std::uint8_t>(s, 1), put<std::uint8_t>(s, 2),
        put<std::uint8_t>(s, 3), put<std::int32_t>(s, 26);
    put(s, -2.0f), put(s, 1.0f), put(s, 7.5f), put<std::uint8_t>(s, 200), put<std::uint8_t>(s, 100),
        put<std::uint8_t>(s, 50), put<std::int32_t>(s, 7);
    const PointCloud c = read_point_cloud(temp_file("a.ply", s));
    REQUIRE(c.size() == 2);
    CHECK(c.positions_kitti[0] == glm::vec3(1.5f, -0.25f, 10.0f));
    CHECK(c.positions_kitti[1] == glm::vec3(-2.0f, 1.0f, 7.5f));
    CHECK(c.colours[1] == std::array<std::uint8_t, 3>{200, 100, 50});
    CHECK(c.class_ids == std::vector<int>{26, 7});
}

TEST_CASE("A truncated binary PLY is refused naming the file", "[cloud]") {
    std::string s =
        "ply\nformat binary_little_endian 1.0\nelement vertex 3\nproperty float x\n"
        "property float y\nproperty float z\nend_header\n";
    put(s, 1.0f), put(s, 2.0f), put(s, 3.0f);
    CHECK_THROWS_WITH(read_point_cloud(temp_file("short.ply", s)),
                      Catch::Contains("short.ply") && Catch::Contains("truncated"));
}

TEST_CASE("An ASCII PCD with packed float rgb and a label reads back", "[cloud]") {
    const std::uint32_t packed = (10u << 16) | (20u << 8) | 30u;
    float rgb;
    std::memcpy(&rgb, &packed, 4);
    char line[128];
    std::snprintf(line, sizeof line, "1 2 3 %.10e 24\n", static_cast<double>(rgb));
    const std::string s = std::string(
                              "# .PCD v0.7\nVERSION 0.7\nFIELDS x y z rgb label\nSIZE 4 4 4 4 4\n"
                              "TYPE F F F F U\nCOUNT 1 1 1 1 1\nWIDTH 1\nHEIGHT 1\n"
                              "VIEWPOINT 0 0 0 1 0 0 0\nPOINTS 1\nDATA ascii\n") +
                          line;
    const PointCloud c = read_point_cloud(temp_file("a.pcd", s));
    REQUIRE(c.size() == 1);
    CHECK(c.positions_kitti[0] == glm::vec3(1, 2, 3));
    CHECK(c.colours[0] == std::array<std::uint8_t, 3>{10, 20, 30});
    CHECK(c.class_ids[0] == 24);
}

TEST_CASE("A binary PCD reads back and NaN points are dropped", "[cloud]") {
    std::string s =
        "VERSION 0.7\nFIELDS x y z rgb label\nSIZE 4 4 4 4 4\nTYPE F F F F U\n"
        "COUNT 1 1 1 1 1\nWIDTH 2\nHEIGHT 1\nPOINTS 2\nDATA binary\n";
    const std::uint32_t packed = (1u << 16) | (2u << 8) | 3u;
    float rgb;
    std::memcpy(&rgb, &packed, 4);
    put(s, 4.0f), put(s, 5.0f), put(s, 6.0f), put(s, rgb), put<std::uint32_t>(s, 26);
    put(s, std::nanf("")), put(s, 0.0f), put(s, 0.0f), put(s, rgb), put<std::uint32_t>(s, 7);
    const PointCloud c = read_point_cloud(temp_file("b.pcd", s));
    REQUIRE(c.size() == 1);
    CHECK(c.positions_kitti[0] == glm::vec3(4, 5, 6));
    CHECK(c.colours[0] == std::array<std::uint8_t, 3>{1, 2, 3});
    CHECK(c.class_ids[0] == 26);
}

TEST_CASE("An XYZ file with a // header maps columns by name", "[cloud]") {
    const PointCloud c =
        read_point_cloud(temp_file("a.xyz",
                                   "//X Y Z R G B Class Luma\n1.000 2.000 3.000 4 5 6 26 0.5\n"
                                   "-1.5 0.25 9 7 8 9 7 0.1\n"));
    REQUIRE(c.size() == 2);
    CHECK(c.positions_kitti[1] == glm::vec3(-1.5f, 0.25f, 9.0f));
    CHECK(c.colours[0] == std::array<std::uint8_t, 3>{4, 5, 6});
    CHECK(c.class_ids == std::vector<int>{26, 7});
}

TEST_CASE("An unknown point cloud extension is refused", "[cloud]") {
    CHECK_THROWS_WITH(read_point_cloud(temp_file("a.las", "x")), Catch::Contains(".las"));
}
