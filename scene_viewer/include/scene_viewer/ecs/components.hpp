#pragma once

/// ECS components: small plain structs, stored contiguously by World. No virtual functions and
/// no GPU ids: a MeshRef names a model of the renderer's ModelLibrary, not a GL buffer.

#include <cstdint>
#include <string>

#include <glm/glm.hpp>

#include "scene_viewer/ecs/view_spec.hpp"

namespace scene_viewer {

/// Pose and size of an upright box in the entity file's KITTI camera frame.
struct Transform {
    glm::vec3 centre_kitti{0.0f};  ///< box centre, metres (x right, y down, z forward)
    double theta_rad = 0.0;        ///< KITTI rotation_y, radians
    glm::vec3 size_whl{1.0f};      ///< W (across), H (vertical), L (along heading), metres
};

/// Model-to-world matrix in the OpenGL world frame, written by the transform system.
struct WorldMatrix {
    glm::mat4 value{1.0f};
};

/// Which model of the ModelLibrary to draw, and how its bounds map onto the unit cube.
struct MeshRef {
    std::uint32_t model = 0;       ///< index into ModelLibrary
    glm::mat4 fit{1.0f};           ///< model frame -> unit cube [-0.5, 0.5]^3
    bool fit_to_transform = true;  ///< false: the model is already in world metres (grid, cloud)
};

/// How a drawable is shaded.
struct Material {
    glm::vec4 colour{1.0f};      ///< class colour, linear 0..1 (exact palette colour / 255)
    bool lit = true;             ///< false: flat colour, no lighting
    bool vertex_colour = false;  ///< use per-vertex colours (point clouds)
    float point_size_px = 2.0f;  ///< size of GL points
    bool procedural = false;     ///< modulate by world-space value noise (sensor renders)
    bool painted = false;        ///< lit: the model's "paint" parts take `paint`
    glm::vec4 paint{1.0f};       ///< display (sRGB-encoded) RGBA 0..1 of the paint
};

/// A camera: what view it takes and the matrices the camera system computed for it.
struct Camera {
    ViewSpec spec;               ///< kind and parameters of the view
    int width_px = 0;            ///< target width
    int height_px = 0;           ///< target height
    glm::mat4 view{1.0f};        ///< world (GL) -> eye
    glm::mat4 projection{1.0f};  ///< eye -> clip
};

/// Back-reference from a scene entity to the entity file it came from.
struct SourceEntity {
    std::int32_t index = -1;  ///< position in EntityDocument::entities; -1 for helpers
    std::string id;           ///< entity id from the file ("ego", "grid", "cloud" for helpers)
    int class_id = 0;         ///< class id from the file
    std::string class_name;   ///< class name from the file ("" for helpers)
};

}  // namespace scene_viewer
