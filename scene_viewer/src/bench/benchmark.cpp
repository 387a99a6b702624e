#include "scene_viewer/bench/benchmark.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <stdexcept>

#include "scene_viewer/assets/image_io.hpp"
#include "stereoscene/support/angles.hpp"

using stereoscene::support::kPi;

namespace scene_viewer {

std::vector<BenchmarkRow> benchmark_rows(int msaa_samples) {
    std::vector<BenchmarkRow> rows = {{"lit fxaa", Shading::lit, Antialias::fxaa},
                                      {"lit none", Shading::lit, Antialias::none},
                                      {"semantic", Shading::semantic, Antialias::none}};
    if (msaa_samples > 1) {
        rows.insert(rows.begin() + 1,
                    {"lit msaa " + std::to_string(msaa_samples), Shading::lit, Antialias::msaa});
    }
    return rows;
}

void BenchmarkOptions::validate() const {
    if (frames < 1 || frames > 100000) throw std::invalid_argument("frames must be in 1..100000");
    if (warmup_frames < 0) throw std::invalid_argument("warmup_frames must be >= 0");
    if (entity_count < 0 || entity_count > 100000)
        throw std::invalid_argument("entity_count must be in 0..100000");
    if (png_repeats < 1) throw std::invalid_argument("png_repeats must be >= 1");
    if (zlib_level < 0 || zlib_level > 9) throw std::invalid_argument("zlib_level must be in 0..9");
}

scene_schema::EntityDocument make_benchmark_document(int count) {
    scene_schema::EntityDocument doc;
    doc.frame.id = "benchmark";
    doc.frame.camera =
        scene_schema::CameraIntrinsics{1242, 375, 721.5377, 721.5377, 609.5593, 172.854, 0.5372};
    auto add = [&](const std::string& cls, int id, double x, double y, double z, double theta,
                   double w, double h, double l) {
        scene_schema::Entity e;
        e.id = cls + "-" + std::to_string(doc.entities.size() + 1);
        e.class_name = cls;
        e.class_id = id;
        e.x = x, e.y = y, e.z = z, e.theta = theta, e.W = w, e.H = h, e.L = l;
        e.method = "benchmark";
        doc.entities.push_back(e);
    };
    const int rows = (count + 4) / 5;
    const double length = 8.0 * rows + 10.0;
    add("road", 7, 0.0, 1.625, 0.5 * length, -kPi / 2, 17.0, 0.05, length);
    add("sidewalk", 8, -10.0, 1.575, 0.5 * length, -kPi / 2, 3.0, 0.15, length);
    add("sidewalk", 8, 10.0, 1.575, 0.5 * length, -kPi / 2, 3.0, 0.15, length);
    for (int i = 0; i < count; ++i) {
        const double x = -6.4 + 3.2 * (i % 5);
        const double z = 8.0 + 8.0 * (i / 5);
        add("car", 26, x, 0.9, z, -kPi / 2 + 0.1 * ((i % 3) - 1), 1.8, 1.5, 4.2);
    }
    return doc;
}

BenchmarkResult run_benchmark(SceneRenderer& renderer, const scene_schema::EntityDocument& document,
                              const RenderOptions& render_options,
                              const BenchmarkOptions& options) {
    options.validate();
    using Clock = std::chrono::steady_clock;
    auto ms_since = [](Clock::time_point t0) {
        return std::chrono::duration<double, std::milli>(Clock::now() - t0).count();
    };
    renderer.load(document, nullptr, render_options);
    ImageRgba8 image;
    for (int i = 0; i < options.warmup_frames; ++i) image = renderer.render_frame();

    BenchmarkResult result;
    result.frames = options.frames;
    result.frame_ms_min = 1e300;
    const auto start = Clock::now();
    for (int i = 0; i < options.frames; ++i) {
        const auto t0 = Clock::now();
        image = renderer.render_frame();
        result.frame_ms_min = std::min(result.frame_ms_min, ms_since(t0));
    }
    result.frame_ms = ms_since(start) / options.frames;
    result.fps = 1000.0 / result.frame_ms;

    const auto png_start = Clock::now();
    for (int i = 0; i < options.png_repeats; ++i) {
        result.png_bytes = encode_png(image, options.zlib_level).size();
    }
    result.png_ms = ms_since(png_start) / options.png_repeats;

    const World& world = renderer.world();
    for (const MeshRef& m : world.meshes.dense()) {
        result.triangles += renderer.models().at(m.model).triangle_count;
    }
    return result;
}

}  // namespace scene_viewer
