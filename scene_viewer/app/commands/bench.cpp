#include "bench.hpp"

#include <cstdio>
#include <stdexcept>

namespace scene_render {

using namespace scene_viewer;

CLI::App* add_bench_command(CLI::App& app, BenchArgs& a) {
    CLI::App* bench = app.add_subcommand("bench", "time frames of a synthetic street scene");
    bench->add_option("--frames", a.options.frames, "timed frames")->capture_default_str();
    bench->add_option("--entities", a.options.entity_count, "cars in the scene")
        ->capture_default_str();
    bench->add_option("--size", a.size, "image size WxH")->capture_default_str();
    bench->add_option("--msaa", a.msaa, "multisample count of the 'lit msaa' row (0 = no such row)")
        ->capture_default_str();
    bench->add_option("--zlib", a.options.zlib_level, "PNG zlib level 0..9")->capture_default_str();
    bench->add_flag("--boxes", a.boxes, "draw boxes instead of glTF models");
    return bench;
}

int run_bench(const BenchArgs& a) {
    RenderOptions o;
    std::tie(o.width_px, o.height_px) = size_flag(a.size, "--size");
    try {
        a.options.validate();
    } catch (const std::invalid_argument& e) {
        usage(e.what(), "bench");
    }
    if (a.msaa < 0 || a.msaa > 16) usage("must be in 0..16", "--msaa");
    const auto classes = read_classes(a.boxes, "");
    auto gpu = start_gpu(classes);
    const auto document = make_benchmark_document(a.options.entity_count);
    const GlInfo gl = gpu->context.info();
    std::printf("renderer: %s; scene: %d cars + road and sidewalks, %dx%d, %s, %d frames\n",
                gl.renderer.c_str(), a.options.entity_count, o.width_px, o.height_px,
                a.boxes ? "boxes" : "glTF models", a.options.frames);
    std::printf("%-16s %10s %10s %10s %8s %8s %9s\n", "shading", "triangles", "ms/frame", "min ms",
                "fps", "PNG ms", "PNG KiB");
    o.msaa_samples = a.msaa;
    for (const BenchmarkRow& row : benchmark_rows(a.msaa)) {
        o.shading = row.shading;
        o.antialias = row.antialias;
        const BenchmarkResult r = run_benchmark(gpu->renderer, document, o, a.options);
        std::printf("%-16s %10zu %10.2f %10.2f %8.1f %8.2f %9.1f\n", row.name.c_str(), r.triangles,
                    r.frame_ms, r.frame_ms_min, r.fps, r.png_ms,
                    static_cast<double>(r.png_bytes) / 1024.0);
    }
    return 0;
}

}  // namespace scene_render
