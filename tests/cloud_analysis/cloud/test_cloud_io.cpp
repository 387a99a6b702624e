#include <catch2/catch.hpp>

#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iomanip>
#include <random>
#include <sstream>

#include <pcl/io/pcd_io.h>
#include <pcl/io/ply_io.h>
#include <pcl/point_types.h>

#include "cloud_analysis/cloud/cloud_io.hpp"
#include "cloud_analysis/cloud/semantic.hpp"

using namespace cloud_analysis;

namespace {

LabeledCloud three_points(const Palette& palette) {
    LabeledCloud c;
    c.width_px = 10;
    c.height_px = 10;
    c.xyz_m = {{1.25f, -0.5f, 20.125f}, {-3.0f, 1.65f, 7.5f}, {0.0f, 0.0f, 79.999f}};
    c.colour = {Rgb{10, 20, 30}, Rgb{255, 0, 128}, Rgb{0, 0, 0}};
    c.class_index = {find_class(palette, "car"), find_class(palette, "road"), kVoidClass};
    c.pixel = {1, 2, 3};
    return c;
}

std::filesystem::path write_temp(const std::string& name, const std::string& bytes) {
    const auto path = std::filesystem::temp_directory_path() / ("stereoscene_test_" + name);
    std::ofstream(path, std::ios::binary) << bytes;
    return path;
}

}  // namespace

TEST_CASE("the xyz writer prints a // header and one fixed-point line per point", "[cloud_io]") {
    const Palette city = load_palette("cityscapes");
    const std::string text = format_xyz(three_points(city), city);
    std::istringstream in(text);
    std::string line;
    std::getline(in, line);
    CHECK(line == "//X Y Z R G B Class Luma");
    std::getline(in, line);
    CHECK(line == "1.250 -0.500 20.125 10 20 30 26 18");
    std::getline(in, line);
    CHECK(line == "-3.000 1.650 7.500 255 0 128 7 91");
    std::getline(in, line);
    CHECK(line == "0.000 0.000 79.999 0 0 0 0 0");
    CHECK_FALSE(std::getline(in, line));
}

TEST_CASE("PCL reads our binary PCD back with positions, packed rgb and labels", "[cloud_io]") {
    const Palette city = load_palette("cityscapes");
    const LabeledCloud cloud = three_points(city);
    const auto path = write_temp("cloud.pcd", format_pcd(cloud, city));
    pcl::PointCloud<pcl::PointXYZRGBL> back;
    REQUIRE(pcl::io::loadPCDFile(path.string(), back) == 0);
    std::filesystem::remove(path);
    REQUIRE(back.size() == 3);
    CHECK(back[0].x == 1.25f);
    CHECK(back[0].z == 20.125f);
    CHECK(int{back[0].r} == 10);
    CHECK(int{back[0].g} == 20);
    CHECK(int{back[0].b} == 30);
    CHECK(back[0].label == 26u);
    CHECK(int{back[1].r} == 255);
    CHECK(int{back[1].b} == 128);
    CHECK(back[1].label == 7u);
    CHECK(back[2].label == 0u);
}

TEST_CASE("PCL reads our binary PLY back with colours and scalar_class", "[cloud_io]") {
    const Palette city = load_palette("cityscapes");
    const LabeledCloud cloud = three_points(city);
    const auto path = write_temp("cloud.ply", format_ply(cloud, city));
    pcl::PCLPointCloud2 blob;
    REQUIRE(pcl::io::loadPLYFile(path.string(), blob) == 0);
    std::filesystem::remove(path);
    REQUIRE(blob.width * blob.height == 3);
    const pcl::PCLPointField* cls = nullptr;
    const pcl::PCLPointField* y = nullptr;
    for (const auto& f : blob.fields) {
        if (f.name == "scalar_class") cls = &f;
        if (f.name == "y") y = &f;
    }
    REQUIRE(cls != nullptr);
    REQUIRE(y != nullptr);
    std::int32_t label = 0;
    float y1 = 0.0f;
    std::memcpy(&label, blob.data.data() + blob.point_step * 1 + cls->offset, 4);
    std::memcpy(&y1, blob.data.data() + blob.point_step * 1 + y->offset, 4);
    CHECK(label == 7);
    CHECK(y1 == 1.65f);
    pcl::PointCloud<pcl::PointXYZRGB> rgb;
    REQUIRE(pcl::io::loadPLYFile(write_temp("cloud2.ply", format_ply(cloud, city)).string(), rgb) ==
            0);
    REQUIRE(rgb.size() == 3);
    CHECK(int{rgb[1].r} == 255);
    CHECK(int{rgb[1].b} == 128);
}

TEST_CASE("the cloud files can leave classes out", "[cloud_io]") {
    const Palette city = load_palette("cityscapes");
    const LabeledCloud all = three_points(city);
    const LabeledCloud no_road = without_classes(all, class_indices(city, {"road"}));
    REQUIRE(no_road.size() == 2);
    CHECK(no_road.class_index[0] == find_class(city, "car"));
    CHECK(no_road.class_index[1] == kVoidClass);
    CHECK(no_road.pixel == std::vector<std::uint32_t>{1, 3});
    CHECK(no_road.colour[1] == Rgb{0, 0, 0});
    const LabeledCloud only_road = without_classes(all, class_indices(city, {"car", "void"}));
    REQUIRE(only_road.size() == 1);
    CHECK(only_road.xyz_m[0].z() == 7.5f);
    CHECK(without_classes(all, {}).size() == 3);
    CHECK_THROWS_WITH(class_indices(city, {"skyy"}), "no class 'skyy' in palette 'cityscapes'");
}

TEST_CASE("cloud formats follow the file extension", "[cloud_io]") {
    CHECK(cloud_format_from_path("a/b.xyz") == CloudFormat::kXyz);
    CHECK(cloud_format_from_path("b.pcd") == CloudFormat::kPcd);
    CHECK(cloud_format_from_path("b.ply") == CloudFormat::kPly);
    CHECK_THROWS_WITH(cloud_format_from_path("b.las"), Catch::Contains(".las"));
}

TEST_CASE("the fast xyz formatter agrees with iostream on random points", "[cloud_io]") {
    const Palette city = load_palette("cityscapes");
    std::mt19937 rng(42);
    std::uniform_real_distribution<float> coord(-90.0f, 90.0f);
    std::uniform_int_distribution<int> byte(0, 255);
    std::uniform_int_distribution<int> cls(0, static_cast<int>(city.classes.size()));
    LabeledCloud cloud;
    // An odd count above 100000: the formatter splits such a cloud over two threads.
    for (int i = 0; i < 150001; ++i) {
        cloud.xyz_m.emplace_back(coord(rng), coord(rng) / 100.0f, coord(rng) * 10.0f);
        cloud.colour.push_back(Rgb{static_cast<std::uint8_t>(byte(rng)),
                                   static_cast<std::uint8_t>(byte(rng)),
                                   static_cast<std::uint8_t>(byte(rng))});
        const int c = cls(rng);
        cloud.class_index.push_back(c == static_cast<int>(city.classes.size())
                                        ? kVoidClass
                                        : static_cast<std::uint16_t>(c));
        cloud.pixel.push_back(static_cast<std::uint32_t>(i));
    }
    // Naive reference: iostream fixed point, "-0.000" printed as "0.000".
    std::ostringstream ref;
    ref << "//X Y Z R G B Class Luma\n" << std::fixed << std::setprecision(3);
    const auto coordinate = [&](float v) {
        std::ostringstream one;
        one << std::fixed << std::setprecision(3) << static_cast<double>(v);
        const std::string text = one.str();
        return text == "-0.000" ? std::string("0.000") : text;
    };
    for (std::size_t i = 0; i < cloud.size(); ++i) {
        const auto& p = cloud.xyz_m[i];
        const auto& c = cloud.colour[i];
        const int id =
            cloud.class_index[i] == kVoidClass ? 0 : city.classes[cloud.class_index[i]].id;
        const int luma = (299 * c[0] + 587 * c[1] + 114 * c[2] + 500) / 1000;
        ref << coordinate(p.x()) << ' ' << coordinate(p.y()) << ' ' << coordinate(p.z()) << ' '
            << int{c[0]} << ' ' << int{c[1]} << ' ' << int{c[2]} << ' ' << id << ' ' << luma
            << '\n';
    }
    CHECK(format_xyz(cloud, city) == ref.str());
}
