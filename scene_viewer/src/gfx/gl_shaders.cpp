#include "gl_shaders.hpp"

#include <stdexcept>
#include <string>

namespace scene_viewer {

namespace {

constexpr const char* kVertexShader = R"(#version 450 core
layout(location = 0) in vec3 a_position;
layout(location = 1) in vec3 a_normal;
layout(location = 2) in vec4 a_colour;
layout(location = 3) in vec2 a_texcoord;
uniform mat4 u_model;
uniform mat4 u_view_projection;
uniform mat3 u_normal_matrix;
uniform float u_point_size;
out vec3 v_normal;
out vec4 v_colour;
out vec2 v_texcoord;
out vec3 v_world;
void main() {
    vec4 world = u_model * vec4(a_position, 1.0);
    v_world = world.xyz;
    gl_Position = u_view_projection * world;
    gl_PointSize = u_point_size;
    v_normal = u_normal_matrix * a_normal;
    v_colour = a_colour;
    v_texcoord = a_texcoord;
}
)";

constexpr const char* kFragmentShader = R"(#version 450 core
in vec3 v_normal;
in vec4 v_colour;
in vec2 v_texcoord;
in vec3 v_world;
uniform vec4 u_colour;
uniform int u_procedural;
uniform int u_lit;
uniform int u_vertex_colour;
uniform int u_textured;
uniform sampler2D u_texture;
uniform vec3 u_light_direction;
uniform float u_ambient;
uniform mat4 u_texture_frame;
out vec4 o_colour;
// Value noise on a lattice hashed from world coordinates (metres) in u_texture_frame (a drive's
// world): fixed to the surface, so every view of a point sees the same texture (what stereo
// matching and odometry need).
float hash3(vec3 p) {
    p = fract(p * 0.3183099 + vec3(0.71, 0.113, 0.419));
    p *= 17.0;
    return fract(p.x * p.y * p.z * (p.x + p.y + p.z));
}
float value_noise(vec3 x) {
    vec3 i = floor(x);
    vec3 f = fract(x);
    f = f * f * (3.0 - 2.0 * f);
    return mix(mix(mix(hash3(i), hash3(i + vec3(1, 0, 0)), f.x),
                   mix(hash3(i + vec3(0, 1, 0)), hash3(i + vec3(1, 1, 0)), f.x), f.y),
               mix(mix(hash3(i + vec3(0, 0, 1)), hash3(i + vec3(1, 0, 1)), f.x),
                   mix(hash3(i + vec3(0, 1, 1)), hash3(i + vec3(1, 1, 1)), f.x), f.y), f.z);
}
void main() {
    vec4 c = u_colour;
    if (u_vertex_colour != 0) c *= v_colour;
    if (u_textured != 0) c *= texture(u_texture, v_texcoord);
    if (u_procedural != 0) {
        // Octaves of 0.6 m, 0.2 m, 7 cm and 2.5 cm cells; 0 mean, about +-0.5 range.
        vec3 p = (u_texture_frame * vec4(v_world, 1.0)).xyz + vec3(1000.0);
        float n = 0.35 * value_noise(p / 0.6) + 0.3 * value_noise(p / 0.2) +
                  0.2 * value_noise(p / 0.07) + 0.15 * value_noise(p / 0.025) - 0.5;
        c.rgb = clamp(c.rgb * (1.0 + 1.2 * n) + vec3(0.18 * n), 0.0, 1.0);
    }
    if (u_lit != 0) {
        vec3 n = normalize(v_normal);
        if (!gl_FrontFacing) n = -n;
        float diffuse = max(dot(n, u_light_direction), 0.0);
        c.rgb *= u_ambient + (1.0 - u_ambient) * diffuse;
    }
    o_colour = c;
}
)";

/// Returns `object` when its `status` (GL_COMPILE_STATUS of a shader, GL_LINK_STATUS of a
/// program) is true; else deletes it and throws std::runtime_error "<what>: <GL info log>".
template <typename GetStatus, typename GetLog, typename Delete>
GLuint checked(GLuint object, GLenum status, GetStatus get_status, GetLog get_log, Delete remove,
               const char* what) {
    GLint ok = 0;
    get_status(object, status, &ok);
    if (ok) return object;
    char log[2048] = {};
    get_log(object, sizeof log, nullptr, log);
    remove(object);
    throw std::runtime_error(std::string(what) + ": " + log);
}

GLuint compile(GLenum type, const char* source) {
    const GLuint shader = glCreateShader(type);
    glShaderSource(shader, 1, &source, nullptr);
    glCompileShader(shader);
    return checked(shader, GL_COMPILE_STATUS, glGetShaderiv, glGetShaderInfoLog, glDeleteShader,
                   "GL shader compile failed");
}

/// Links a vertex and a fragment shader; throws std::runtime_error with the GL log.
GLuint link(const char* vertex_source, const char* fragment_source) {
    const GLuint vs = compile(GL_VERTEX_SHADER, vertex_source);
    GLuint fs = 0;
    try {
        fs = compile(GL_FRAGMENT_SHADER, fragment_source);
    } catch (...) {
        glDeleteShader(vs);
        throw;
    }
    const GLuint program = glCreateProgram();
    glAttachShader(program, vs);
    glAttachShader(program, fs);
    glLinkProgram(program);
    glDeleteShader(vs);
    glDeleteShader(fs);
    return checked(program, GL_LINK_STATUS, glGetProgramiv, glGetProgramInfoLog, glDeleteProgram,
                   "GL program link failed");
}

// A triangle covering the viewport at window depth 0, from gl_VertexID alone (no vertex buffer).
constexpr const char* kFullscreenVertexShader = R"(#version 450 core
void main() {
    vec2 p = vec2((gl_VertexID << 1) & 2, gl_VertexID & 2);
    gl_Position = vec4(p * 2.0 - 1.0, -1.0, 1.0);
}
)";

// FXAA 3.11, PC quality preset 12 (T. Lottes, "FXAA", NVIDIA whitepaper 2011, and its reference
// Fxaa3_11.h), in two passes because llvmpipe runs both sides of a branch: the mark pass copies
// every pixel and sets depth 0 on luma edges, then the blend pass runs only there (early depth
// test EQUAL 0), walks along each edge to its ends and blends across it by the pixel's place on
// the span. Luma is Rec. 601 of the stored RGB.
#define STEREOSCENE_FXAA_COMMON                                                           \
    "#version 450 core\n"                                                                 \
    "uniform sampler2D u_source;\n"                                                       \
    "out vec4 o_colour;\n"                                                                \
    "const float kEdgeThreshold = 0.166;  // contrast needed for an edge, share of max\n" \
    "const float kEdgeThresholdMin = 0.0833;  // ... and at least this absolute luma\n"   \
    "float luma(vec4 c) { return dot(c.rgb, vec3(0.299, 0.587, 0.114)); }\n"              \
    "// FXAA's local contrast test of a pixel (m) and its 4 neighbours.\n"                \
    "bool on_edge(float m, float n, float s, float e, float w, out float range) {\n"      \
    "    float range_max = max(max(n, w), max(e, max(s, m)));\n"                          \
    "    range = range_max - min(min(n, w), min(e, min(s, m)));\n"                        \
    "    return range >= max(kEdgeThresholdMin, range_max * kEdgeThreshold);\n"           \
    "}\n"

constexpr const char* kFxaaMarkShader = STEREOSCENE_FXAA_COMMON R"(
// Texel fetches: cheaper than filtered samples on llvmpipe; clamped like CLAMP_TO_EDGE.
#define LUMA_AT(dx, dy) luma(texelFetch(u_source, clamp(p + ivec2(dx, dy), ivec2(0), hi), 0))
void main() {
    ivec2 p = ivec2(gl_FragCoord.xy);
    ivec2 hi = textureSize(u_source, 0) - 1;
    vec4 rgba_m = texelFetch(u_source, p, 0);
    float range;
    bool edge = on_edge(luma(rgba_m), LUMA_AT(0, 1), LUMA_AT(0, -1), LUMA_AT(1, 0),
                        LUMA_AT(-1, 0), range);
    o_colour = rgba_m;
    gl_FragDepth = edge ? 0.0 : 1.0;
}
)";

constexpr const char* kFxaaBlendShader = STEREOSCENE_FXAA_COMMON R"(
const float kSubpix = 0.75;  // subpixel aliasing removal, 0 off .. 1 softer
const int kSearchSteps = 5;
const float kSearchStep[5] = float[](1.0, 1.5, 2.0, 4.0, 12.0);  // pixels per search step
// Texel offsets must be constant expressions.
#define LUMA_AT(dx, dy) luma(textureLodOffset(u_source, pos, 0.0, ivec2(dx, dy)))
void main() {
    vec2 rcp = 1.0 / vec2(textureSize(u_source, 0));
    vec2 pos = gl_FragCoord.xy * rcp;
    vec4 rgba_m = textureLod(u_source, pos, 0.0);
    float luma_m = luma(rgba_m);
    float luma_s = LUMA_AT(0, 1);
    float luma_e = LUMA_AT(1, 0);
    float luma_n = LUMA_AT(0, -1);
    float luma_w = LUMA_AT(-1, 0);
    float range;
    if (!on_edge(luma_m, luma_n, luma_s, luma_e, luma_w, range)) {
        o_colour = rgba_m;  // the mark pass's test again: the pass stays right on its own
        return;
    }
    float luma_nw = LUMA_AT(-1, -1);
    float luma_se = LUMA_AT(1, 1);
    float luma_ne = LUMA_AT(1, -1);
    float luma_sw = LUMA_AT(-1, 1);

    // Edge direction: horizontal edges have a strong vertical second derivative.
    float edge_horz = abs(-2.0 * luma_w + luma_nw + luma_sw) +
                      2.0 * abs(-2.0 * luma_m + luma_n + luma_s) +
                      abs(-2.0 * luma_e + luma_ne + luma_se);
    float edge_vert = abs(-2.0 * luma_s + luma_sw + luma_se) +
                      2.0 * abs(-2.0 * luma_m + luma_w + luma_e) +
                      abs(-2.0 * luma_n + luma_nw + luma_ne);
    bool horz_span = edge_horz >= edge_vert;
    float subpix_a = 2.0 * (luma_n + luma_s + luma_w + luma_e) +
                     (luma_nw + luma_sw + luma_ne + luma_se);
    float length_sign = horz_span ? rcp.y : rcp.x;
    if (!horz_span) {
        luma_n = luma_w;
        luma_s = luma_e;
    }
    // The side of the edge with the larger gradient.
    float gradient_n = luma_n - luma_m;
    float gradient_s = luma_s - luma_m;
    bool pair_n = abs(gradient_n) >= abs(gradient_s);
    float gradient = max(abs(gradient_n), abs(gradient_s));
    if (pair_n) length_sign = -length_sign;
    float luma_nn = pair_n ? luma_n + luma_m : luma_s + luma_m;
    float subpix_c = clamp(abs(subpix_a * (1.0 / 12.0) - luma_m) / range, 0.0, 1.0);

    // Walk both ways along the edge, half a pixel towards the pair, until the luma leaves it.
    vec2 pos_b = pos;
    vec2 off_np = horz_span ? vec2(rcp.x, 0.0) : vec2(0.0, rcp.y);
    if (horz_span) {
        pos_b.y += length_sign * 0.5;
    } else {
        pos_b.x += length_sign * 0.5;
    }
    float gradient_scaled = gradient * 0.25;
    bool luma_m_lt_zero = luma_m - luma_nn * 0.5 < 0.0;
    vec2 pos_n = pos_b - off_np * kSearchStep[0];
    vec2 pos_p = pos_b + off_np * kSearchStep[0];
    float luma_end_n = luma(textureLod(u_source, pos_n, 0.0)) - luma_nn * 0.5;
    float luma_end_p = luma(textureLod(u_source, pos_p, 0.0)) - luma_nn * 0.5;
    bool done_n = abs(luma_end_n) >= gradient_scaled;
    bool done_p = abs(luma_end_p) >= gradient_scaled;
    if (!done_n) pos_n -= off_np * kSearchStep[1];
    if (!done_p) pos_p += off_np * kSearchStep[1];
    for (int i = 2; i < kSearchSteps && !(done_n && done_p); ++i) {
        if (!done_n) luma_end_n = luma(textureLod(u_source, pos_n, 0.0)) - luma_nn * 0.5;
        if (!done_p) luma_end_p = luma(textureLod(u_source, pos_p, 0.0)) - luma_nn * 0.5;
        done_n = abs(luma_end_n) >= gradient_scaled;
        done_p = abs(luma_end_p) >= gradient_scaled;
        if (!done_n) pos_n -= off_np * kSearchStep[i];
        if (!done_p) pos_p += off_np * kSearchStep[i];
    }

    // Blend across the edge by the distance to the nearer end of the span, or by the subpixel
    // contrast, whichever is larger.
    float dst_n = horz_span ? pos.x - pos_n.x : pos.y - pos_n.y;
    float dst_p = horz_span ? pos_p.x - pos.x : pos_p.y - pos.y;
    bool direction_n = dst_n < dst_p;
    bool good_span = ((direction_n ? luma_end_n : luma_end_p) < 0.0) != luma_m_lt_zero;
    float pixel_offset = good_span ? 0.5 - min(dst_n, dst_p) / (dst_n + dst_p) : 0.0;
    float subpix_f = (-2.0 * subpix_c + 3.0) * subpix_c * subpix_c;
    float offset = max(pixel_offset, subpix_f * subpix_f * kSubpix);
    if (horz_span) {
        pos.y += offset * length_sign;
    } else {
        pos.x += offset * length_sign;
    }
    o_colour = textureLod(u_source, pos, 0.0);
}
)";

}  // namespace

GLuint link_scene_program() { return link(kVertexShader, kFragmentShader); }

GLuint link_fxaa_mark_program() { return link(kFullscreenVertexShader, kFxaaMarkShader); }

GLuint link_fxaa_blend_program() { return link(kFullscreenVertexShader, kFxaaBlendShader); }

}  // namespace scene_viewer
