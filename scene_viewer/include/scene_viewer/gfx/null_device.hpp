#pragma once

/// A backend that draws nothing and records every call, for tests of the ECS and systems
/// (after bgfx's renderer_noop and Filament's NoopDriver).

#include <vector>

#include "scene_viewer/gfx/device.hpp"

namespace scene_viewer {

class NullDevice final : public Device {
  public:
    MeshHandle create_mesh(const MeshData& mesh) override;
    TextureHandle create_texture(const ImageRgba8& image) override;
    void destroy_mesh(MeshHandle mesh) override;
    void destroy_texture(TextureHandle texture) override;
    void begin_frame(const FrameSetup& setup) override;
    void draw(const DrawCall& call) override;
    void end_frame() override;
    /// A cleared image of the frame size (clear colour), so callers can run unchanged.
    ImageRgba8 read_pixels() override;
    /// Depth 1 (nothing drawn) everywhere, of the frame size.
    std::vector<float> read_depth() override;

    /// Recorded state.
    std::vector<MeshData> meshes;  ///< every mesh created; handle id = index + 1
    int textures_created = 0;
    int meshes_destroyed = 0;
    int textures_destroyed = 0;
    int frames_begun = 0;
    int frames_ended = 0;
    int fxaa_passes = 0;  ///< frames ended with the FXAA post-process pass
    FrameSetup last_setup;
    std::vector<DrawCall> draws;  ///< draws of the current (last) frame
};

}  // namespace scene_viewer
