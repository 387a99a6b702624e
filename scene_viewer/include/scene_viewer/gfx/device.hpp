#pragma once

/// The narrow drawing interface between the render system and a graphics backend (the GL backend
/// for real images, the null backend that records calls for tests). Resources are named by typed
/// handles; no backend type leaks through this header.

#include <cstdint>
#include <vector>

#include <glm/glm.hpp>

#include "scene_viewer/assets/model.hpp"

namespace scene_viewer {

/// A mesh uploaded to the device; id 0 is "none".
struct MeshHandle {
    std::uint32_t id = 0;
    bool valid() const { return id != 0; }
};

/// A texture uploaded to the device; id 0 is "none".
struct TextureHandle {
    std::uint32_t id = 0;
    bool valid() const { return id != 0; }
};

enum class Topology { triangles, lines, points };

/// CPU geometry to upload; optional arrays are empty or have positions.size() entries.
struct MeshData {
    Topology topology = Topology::triangles;
    std::vector<glm::vec3> positions;
    std::vector<glm::vec3> normals;      ///< optional (lit triangles need them)
    std::vector<glm::vec4> colours;      ///< optional per-vertex colours, 0..1
    std::vector<glm::vec2> texcoords;    ///< optional
    std::vector<std::uint32_t> indices;  ///< optional; without, vertices are drawn in order
};

/// Per-frame state: target size, clear colour, lighting.
struct FrameSetup {
    int width_px = 0;                                ///< target width
    int height_px = 0;                               ///< target height
    glm::vec4 clear_colour{0.0f, 0.0f, 0.0f, 0.0f};  ///< RGBA 0..1
    int msaa_samples = 0;                            ///< 0 or 1: no multisampling
    bool fxaa = false;                               ///< end_frame runs FXAA (msaa_samples <= 1)
    glm::vec3 light_direction{0.3f, 1.0f, 0.4f};     ///< towards the light, GL world frame
    float ambient = 0.35f;                           ///< ambient share of the lit colour, 0..1
    /// GL world -> the frame the procedural noise is fixed to: a drive's world, so the texture
    /// stays on the surfaces while the camera moves (identity: this frame's own world).
    glm::mat4 texture_frame{1.0f};
};

/// One draw of one mesh.
struct DrawCall {
    MeshHandle mesh;
    TextureHandle texture;            ///< multiplies the colour when valid
    glm::mat4 model{1.0f};            ///< model -> world (GL frame)
    glm::mat4 view_projection{1.0f};  ///< world -> clip
    glm::vec4 colour{1.0f};           ///< RGBA 0..1
    bool lit = true;                  ///< directional + ambient, else flat colour
    bool vertex_colour = false;       ///< multiply by per-vertex colours
    float point_size_px = 1.0f;       ///< for Topology::points
    bool procedural = false;  ///< modulate by value noise fixed in FrameSetup::texture_frame
};

/// The backend interface. One frame: begin_frame, draw..., end_frame (MSAA resolve or FXAA pass),
/// then read_pixels. begin_frame throws std::invalid_argument for a setup asking for both MSAA and
/// FXAA.
class Device {
  public:
    virtual ~Device() = default;
    virtual MeshHandle create_mesh(const MeshData& mesh) = 0;
    virtual TextureHandle create_texture(const ImageRgba8& image) = 0;
    virtual void destroy_mesh(MeshHandle mesh) = 0;
    virtual void destroy_texture(TextureHandle texture) = 0;
    virtual void begin_frame(const FrameSetup& setup) = 0;
    virtual void draw(const DrawCall& call) = 0;
    virtual void end_frame() = 0;
    /// The last frame as RGBA8, row 0 at the top.
    virtual ImageRgba8 read_pixels() = 0;
    /// The last frame's window depth (0 near .. 1 far plane or nothing drawn), row 0 at the top;
    /// only for frames without multisampling.
    virtual std::vector<float> read_depth() = 0;
};

}  // namespace scene_viewer
