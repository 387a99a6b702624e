#include <catch2/catch.hpp>

#include <filesystem>
#include <fstream>
#include <limits>

#include "../sample_inputs.hpp"
#include "cloud_analysis/pipeline/pipeline.hpp"

using namespace cloud_analysis;

namespace {
const std::filesystem::path kKitti = std::filesystem::path(STEREOSCENE_SHARED_DATA_DIR) / "kitti15";

InputPaths sample_paths() { return test_samples::synthetic_paths(); }
}  // namespace

TEST_CASE("the KITTI layout finds images, semantics and the raw calibration", "[pipeline][kitti]") {
    const InputPaths p = kitti_layout(kKitti, "000000_10");
    CHECK(p.left == kKitti / "image_2" / "000000_10.png");
    CHECK(p.right == kKitti / "image_3" / "000000_10.png");
    CHECK(p.semantic == kKitti / "semantic_rgb" / "000000_10.png");
    CHECK(p.calibration == kKitti / "calib" / "calib_cam_to_cam.txt");
    // 000046_10 has no semantic image: the path stays empty rather than naming a missing file.
    CHECK(kitti_layout(kKitti, "000046_10").semantic.empty());
}

TEST_CASE("the bundled sample runs through the chain into a labelled metric cloud", "[pipeline]") {
    const AnalyseOptions options;
    const LoadedInputs in = load_inputs(sample_paths(), options);
    CHECK(in.left.channels == 1);
    CHECK(in.semantic.channels == 3);
    const AnalyseResult r = analyse(in, options);
    CHECK(r.cloud.size() > 50000);
    CHECK(r.classes.void_pixels == 0);
    REQUIRE(r.timings.size() == 3);
    CHECK(r.timings[0].stage == "disparity");
    CHECK(r.cloud_points == r.cloud.size());
    CHECK(r.points.xyz_m.empty());
    // Entities only: no cloud, the extractor's points straight from the disparity.
    AnalyseOptions by_class = options;
    ClassSelection selection;
    selection.column_mask.assign(in.palette.classes.size(), 0);
    selection.keep_pixels.assign(in.palette.classes.size(), 1);
    by_class.class_points_only = selection;
    const AnalyseResult p = analyse(in, by_class);
    CHECK(p.cloud.size() == 0);
    CHECK(p.cloud_points == r.cloud.size());
    REQUIRE(p.points.xyz_m.size() == in.palette.classes.size());
    std::size_t labelled = 0;
    for (const auto& k : r.cloud.class_index) labelled += k != kVoidClass ? 1 : 0;
    std::size_t taken = 0;
    for (const auto& pts : p.points.xyz_m) taken += pts.size();
    CHECK(taken > 0);
    CHECK(taken <= labelled);  // within the extractor's depth limit
    const nlohmann::json source = describe_run(in, options, "test");
    CHECK(source["calibration"]["baseline_m"] == 0.54);
    CHECK(source["disparity"]["block_size"] == options.disparity.block_size);
}

TEST_CASE("inputs of different sizes are refused before any work, naming the file",
          "[pipeline][kitti]") {
    InputPaths p = sample_paths();
    p.right = kKitti / "image_3" / "000000_10.png";
    REQUIRE_THROWS_WITH(
        load_inputs(p, AnalyseOptions{}),
        Catch::Contains("right image is 1242x375") && Catch::Contains("000000_10.png"));
    p = sample_paths();
    p.semantic = kKitti / "semantic_rgb" / "000000_10.png";
    REQUIRE_THROWS_WITH(load_inputs(p, AnalyseOptions{}),
                        Catch::Contains("semantic image is 1242x375"));
    p = sample_paths();
    p.calibration = kKitti / "calib" / "calib_cam_to_cam.txt";  // made for 1242x375 images
    REQUIRE_THROWS_WITH(load_inputs(p, AnalyseOptions{}),
                        Catch::Contains("calibration is for 1242x375"));
    AnalyseOptions raw;
    raw.raw = true;  // the YAML calibration has no distortion: nothing to rectify with
    REQUIRE_THROWS_WITH(load_inputs(sample_paths(), raw), Catch::Contains("cannot rectify"));
}

TEST_CASE("a corrupt image is reported as such with its file", "[pipeline][io]") {
    const auto bad = std::filesystem::temp_directory_path() / "stereoscene_test_corrupt.png";
    std::ofstream(bad, std::ios::binary) << "\x89PNG\r\n\x1a\n truncated";
    InputPaths p = sample_paths();
    p.left = bad;
    REQUIRE_THROWS_WITH(
        load_inputs(p, AnalyseOptions{}),
        Catch::Contains("cannot decode image") && Catch::Contains("stereoscene_test_corrupt.png"));
    std::filesystem::remove(bad);
}

TEST_CASE("raw KITTI input is undistorted and rectified to the S_rect size", "[pipeline][kitti]") {
    AnalyseOptions options;
    options.raw = true;
    const LoadedInputs in = load_inputs(kitti_layout(kKitti, "000000_10"), options);
    const AnalyseResult r = analyse(in, options);
    CHECK(r.timings[0].stage == "rectify");
    CHECK(r.disparity.width_px == 1242);
    CHECK(r.disparity.height_px == 375);
    CHECK(r.cloud.size() > 1000);
}

TEST_CASE("rectifying with no distortion and identity rotation leaves the image unchanged",
          "[calibration]") {
    ImageU8 img{32, 16, 1, std::vector<std::uint8_t>(32 * 16)};
    for (std::size_t i = 0; i < img.data.size(); ++i)
        img.data[i] = static_cast<std::uint8_t>(i * 7);
    RawCamera cam;
    cam.K << 30, 0, 16, 0, 30, 8, 0, 0, 1;
    cam.distortion = {0, 0, 0, 0, 0};
    cam.P_rect.leftCols<3>() = cam.K;
    StereoCamera rig;
    const ImageU8 out = rectify_image(img, cam, rig);
    CHECK(out.data == img.data);
}

TEST_CASE("a textureless pair gives an empty disparity, reported as an error", "[pipeline]") {
    const auto dir = std::filesystem::temp_directory_path() / "stereoscene_test_flat";
    std::filesystem::create_directories(dir);
    const ImageU8 flat{200, 60, 1, std::vector<std::uint8_t>(200 * 60, 90)};
    std::ofstream(dir / "flat.png", std::ios::binary) << encode_png(flat);
    std::ofstream(dir / "calib.yaml") << "fx: 100\nfy: 100\ncx: 100\ncy: 30\nbaseline_m: 0.5\n";
    InputPaths p;
    p.left = p.right = dir / "flat.png";
    p.calibration = dir / "calib.yaml";
    AnalyseOptions options;
    options.disparity.num_disparities = 32;
    const LoadedInputs in = load_inputs(p, options);
    REQUIRE_THROWS_WITH(analyse(in, options),
                        Catch::Contains("empty disparity") && Catch::Contains("flat.png"));
    std::filesystem::remove_all(dir);
}

TEST_CASE("images are read as they are: grey PNGs grey, colour PNGs RGB, 16-bit refused",
          "[pipeline][io]") {
    const auto dir = std::filesystem::temp_directory_path() / "stereoscene_test_read_image";
    std::filesystem::create_directories(dir);
    const auto write = [&](const std::string& name, const std::string& bytes) {
        std::ofstream(dir / name, std::ios::binary) << bytes;
        return dir / name;
    };
    ImageU8 grey{3, 2, 1, {0, 50, 100, 150, 200, 250}};
    ImageU8 rgb{2, 1, 3, {255, 0, 0, 10, 20, 30}};
    const auto grey_png = write("grey.png", encode_png(grey));
    const auto rgb_png = write("rgb.png", encode_png(rgb));
    // A 16-bit grey PNG (KITTI's disparity format): refused in every mode, not cut to 8 bits.
    const DisparityMap d{2, 1, {1.0f, 200.0f}};
    const auto grey16_png = write("grey16.png", encode_kitti_disparity_png(d));

    const ImageU8 g = read_image(grey_png);
    CHECK(g.channels == 1);
    CHECK(g.data == grey.data);
    const ImageU8 c = read_image(rgb_png);
    CHECK(c.channels == 3);
    CHECK(c.data == rgb.data);
    for (const ImageMode mode : {ImageMode::kAsIs, ImageMode::kGrey, ImageMode::kColour}) {
        CHECK_THROWS_WITH(read_image(grey16_png, mode), Catch::Contains("16-bit samples refused") &&
                                                            Catch::Contains("grey16.png"));
    }
    CHECK(read_image(grey_png, ImageMode::kColour).channels == 3);
    CHECK(read_image(rgb_png, ImageMode::kGrey).channels == 1);
    std::filesystem::remove_all(dir);
}

TEST_CASE("the depth edge band is on by default whichever path makes the classes", "[pipeline]") {
    AnalyseOptions o;
    CHECK(o.reproject.depth_edge_step_m == 0.8);
    CHECK(o.semantics == "auto");  // labels when a semantic image is given, else geometry
    o.reproject.depth_edge_step_m = 0.0;
    CHECK_NOTHROW(o.validate());
    for (const double bad : {-1.0, std::numeric_limits<double>::infinity()}) {
        o.reproject.depth_edge_step_m = bad;
        CHECK_THROWS_WITH(o.validate(), Catch::Contains("depth_edge_step_m"));
    }
}

TEST_CASE("a calibration asking for a rectified image over the pixel limit is refused up front",
          "[pipeline][calibration]") {
    const auto dir = std::filesystem::temp_directory_path() / "stereoscene_test_huge_rectified";
    std::filesystem::create_directories(dir);
    const ImageU8 small{200, 60, 1, std::vector<std::uint8_t>(200 * 60, 90)};
    std::ofstream(dir / "small.png", std::ios::binary) << encode_png(small);
    std::ofstream(dir / "calib.yaml") << "fx: 100\nfy: 100\ncx: 100\ncy: 30\nbaseline_m: 0.5\n"
                                         "width: 20000\nheight: 10000\n"
                                         "distortion: [0, 0, 0, 0, 0]\n";
    InputPaths p;
    p.left = p.right = dir / "small.png";
    p.calibration = dir / "calib.yaml";
    AnalyseOptions options;
    options.raw = true;
    REQUIRE_THROWS_WITH(load_inputs(p, options), Catch::Contains("rectified image of") &&
                                                     Catch::Contains("calib.yaml") &&
                                                     Catch::Contains("--max-pixels"));
    options.raw = false;  // as rectified input, the size is checked against the images
    REQUIRE_THROWS_WITH(load_inputs(p, options), Catch::Contains("calibration is for 20000x10000"));
    std::filesystem::remove_all(dir);
}
