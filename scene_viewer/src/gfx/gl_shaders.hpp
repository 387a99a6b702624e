#pragma once

/// The GL backend's GLSL programs: the scene shader (lit, flat, textured, vertex-coloured and
/// procedural surfaces) and the two passes of FXAA. Private to the GL backend.

#define GL_GLEXT_PROTOTYPES
#include <GL/gl.h>
#include <GL/glext.h>

namespace scene_viewer {

/// Compiles and links the scene program; throws std::runtime_error with the GL log.
GLuint link_scene_program();

/// FXAA's mark pass: copies every pixel and sets depth 0 on luma edges.
GLuint link_fxaa_mark_program();

/// FXAA's blend pass, run where the mark pass set depth 0.
GLuint link_fxaa_blend_program();

}  // namespace scene_viewer
