#pragma once

/// How a frame is rendered: size, view, shading and antialiasing. Read by the build system and
/// the renderer; includes nothing of either.

#include <cstdint>
#include <string>

#include <glm/glm.hpp>

#include "scene_viewer/ecs/view_spec.hpp"

namespace scene_viewer {

enum class Shading {
    lit,       ///< directional + ambient light, class colours, antialiased (RenderOptions)
    semantic,  ///< exact palette colours, no lighting, no MSAA (pixel-checkable)
    instance,  ///< flat (labelId, instance, 0) / 255 per entity, no MSAA (KITTI instance ids)
};

/// "lit" / "semantic" / "instance" -> Shading; throws std::invalid_argument otherwise.
Shading parse_shading(const std::string& name);

/// How lit shading smooths its edges (semantic and instance shading never do).
enum class Antialias {
    fxaa,  ///< FXAA 3.11 pass over the single-sample image (~7 ms at 1280x720 on llvmpipe)
    msaa,  ///< multisampling, RenderOptions::msaa_samples (~25 ms at 4x, 1280x720, llvmpipe)
    none,  ///< hard edges
};

/// "fxaa" / "msaa" / "none" -> Antialias; throws std::invalid_argument otherwise.
Antialias parse_antialias(const std::string& name);

/// Largest accepted image side, pixels.
inline constexpr int kMaxImageSide = 16384;
/// Largest accepted pixels x samples of one frame (2^28: 16384^2 with one single-sample target,
/// about 2 GB of colour and depth; MSAA counts its samples, FXAA's second target 2).
inline constexpr long long kMaxFrameSamples = 1LL << 28;

struct RenderOptions {
    int width_px = 1242;                    ///< image width, pixels, 1..kMaxImageSide
    int height_px = 375;                    ///< image height, pixels, 1..kMaxImageSide
    ViewSpec view;                          ///< camera; camera-view intrinsics come from the file
    bool fit_bev = true;                    ///< bev: frame every entity (ignores bev_* of view)
    Shading shading = Shading::lit;         ///< lit or semantic
    Antialias antialias = Antialias::fxaa;  ///< lit: edge smoothing; semantic, instance: none
    int msaa_samples = 4;                   ///< lit, Antialias::msaa: multisample count (0 = off)
    bool grid = true;                       ///< bev: draw a 1 m ground grid (10 m lines darker)
    bool ego = true;                        ///< chase/bev/free: draw the ego car at the camera
    float point_size_px = 2.0f;             ///< point cloud overlay: point size, pixels
    bool keep_alpha = false;                ///< keep alpha 0 where nothing was drawn (compositing)
    bool procedural_texture = false;        ///< lit: world-space noise texture on every surface
    /// lit: vehicles wear the world's car paints (vehicle_paint()) where their models have a
    /// "paint" material, instead of the model's own colour (the class colour).
    bool vehicle_paints = false;
    std::uint64_t paint_seed = 0;   ///< vehicle_paints: the seed of the draws (vehicle_paint())
    glm::mat4 texture_frame{1.0f};  ///< GL world -> the noise's frame (FrameSetup)
    /// Throws std::invalid_argument naming the bad field.
    void validate() const;
};

}  // namespace scene_viewer
