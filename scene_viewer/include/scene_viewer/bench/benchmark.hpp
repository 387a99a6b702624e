#pragma once

/// A frame-rate benchmark: one renderer, one uploaded scene, many frames with readback, and the
/// PNG encoding timed separately.

#include <string>
#include <vector>

#include "scene_schema/entities.hpp"
#include "scene_viewer/render/scene_renderer.hpp"

namespace scene_viewer {

struct BenchmarkOptions {
    int frames = 60;        ///< timed frames
    int warmup_frames = 3;  ///< untimed frames first (shader compile, first upload)
    int entity_count = 50;  ///< cars in the synthetic scene
    int png_repeats = 5;    ///< PNG encodings timed
    int zlib_level = 1;     ///< PNG zlib level 0..9
    /// Throws std::invalid_argument naming the bad field.
    void validate() const;
};

struct BenchmarkResult {
    int frames = 0;
    double frame_ms = 0.0;      ///< mean render + readback per frame, milliseconds
    double frame_ms_min = 0.0;  ///< fastest frame, milliseconds
    double fps = 0.0;           ///< 1000 / frame_ms
    double png_ms = 0.0;        ///< mean PNG encoding, milliseconds
    std::size_t png_bytes = 0;  ///< size of one encoded frame
    std::size_t triangles = 0;  ///< triangles drawn per frame
};

/// One row of the benchmark table: a shading and its antialiasing.
struct BenchmarkRow {
    std::string name;     ///< the row's label, e.g. "lit msaa 4"
    Shading shading;      ///< shading of the row
    Antialias antialias;  ///< antialiasing of the row
};

/// The rows to time: the default (lit fxaa) first, then what it replaces (msaa with
/// `msaa_samples`, only when above 1) and what it costs over none, then semantic.
std::vector<BenchmarkRow> benchmark_rows(int msaa_samples);

/// A street of `count` cars (rows of 5 lanes), with road and sidewalks, and camera intrinsics.
scene_schema::EntityDocument make_benchmark_document(int count);

/// Loads `document` once, then times `options.frames` frames of `renderer`.
BenchmarkResult run_benchmark(SceneRenderer& renderer, const scene_schema::EntityDocument& document,
                              const RenderOptions& render_options, const BenchmarkOptions& options);

}  // namespace scene_viewer
