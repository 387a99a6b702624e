#include "scene_viewer/gfx/gl_device.hpp"

#include <algorithm>
#include <stdexcept>
#include <string>
#include <unordered_map>

#define GL_GLEXT_PROTOTYPES
#include <GL/gl.h>
#include <GL/glext.h>
#include <glm/gtc/type_ptr.hpp>

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
out vec4 o_colour;
// Value noise on a lattice hashed from world coordinates (metres): fixed to the surface, so
// every view of a point sees the same texture (what stereo matching needs).
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
        vec3 p = v_world + vec3(1000.0);
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

struct GpuMesh {
    GLuint vao = 0;
    GLuint buffers[5] = {};  // positions, normals, colours, texcoords, indices
    GLenum mode = GL_TRIANGLES;
    GLsizei count = 0;
    bool indexed = false;
};

class GlDevice final : public Device {
  public:
    GlDevice() {
        program_ = link(kVertexShader, kFragmentShader);
        try {
            fxaa_mark_program_ = link(kFullscreenVertexShader, kFxaaMarkShader);
            fxaa_blend_program_ = link(kFullscreenVertexShader, kFxaaBlendShader);
        } catch (...) {
            glDeleteProgram(fxaa_mark_program_);
            glDeleteProgram(program_);
            throw;
        }
        for (GLuint program : {fxaa_mark_program_, fxaa_blend_program_})
            glProgramUniform1i(program, glGetUniformLocation(program, "u_source"), 0);
        glCreateVertexArrays(1, &empty_vao_);
        auto at = [this](const char* name) { return glGetUniformLocation(program_, name); };
        u_ = Uniforms{at("u_model"),           at("u_view_projection"), at("u_normal_matrix"),
                      at("u_point_size"),      at("u_colour"),          at("u_lit"),
                      at("u_vertex_colour"),   at("u_textured"),        at("u_texture"),
                      at("u_light_direction"), at("u_ambient"),         at("u_procedural")};
        glEnable(GL_PROGRAM_POINT_SIZE);
    }

    ~GlDevice() override {
        for (auto& [id, mesh] : meshes_) release(mesh);
        for (auto& [id, tex] : textures_) glDeleteTextures(1, &tex);
        release_targets();
        glDeleteVertexArrays(1, &empty_vao_);
        glDeleteProgram(fxaa_blend_program_);
        glDeleteProgram(fxaa_mark_program_);
        glDeleteProgram(program_);
    }

    GlDevice(const GlDevice&) = delete;
    GlDevice& operator=(const GlDevice&) = delete;

    MeshHandle create_mesh(const MeshData& data) override {
        const std::size_t n = data.positions.size();
        auto check = [&](std::size_t size, const char* what) {
            if (size != 0 && size != n)
                throw std::invalid_argument(std::string("mesh ") + what +
                                            " count differs from the position count");
        };
        check(data.normals.size(), "normal");
        check(data.colours.size(), "colour");
        check(data.texcoords.size(), "texcoord");
        for (std::uint32_t i : data.indices) {
            if (i >= n) throw std::invalid_argument("mesh index out of range");
        }
        GpuMesh mesh;
        glCreateVertexArrays(1, &mesh.vao);
        glCreateBuffers(5, mesh.buffers);
        auto attribute = [&](int slot, const void* bytes, std::size_t size, int components,
                             const float* constant) {
            if (size > 0) {
                glNamedBufferStorage(mesh.buffers[slot], static_cast<GLsizeiptr>(size), bytes, 0);
                glVertexArrayVertexBuffer(mesh.vao, static_cast<GLuint>(slot), mesh.buffers[slot],
                                          0, static_cast<GLsizei>(components * sizeof(float)));
                glVertexArrayAttribFormat(mesh.vao, static_cast<GLuint>(slot), components, GL_FLOAT,
                                          GL_FALSE, 0);
                glVertexArrayAttribBinding(mesh.vao, static_cast<GLuint>(slot),
                                           static_cast<GLuint>(slot));
                glEnableVertexArrayAttrib(mesh.vao, static_cast<GLuint>(slot));
            } else {
                glDisableVertexArrayAttrib(mesh.vao, static_cast<GLuint>(slot));
                glVertexAttrib4fv(static_cast<GLuint>(slot), constant);
            }
        };
        attribute(0, data.positions.data(), n * sizeof(glm::vec3), 3, nullptr);
        const float up[4] = {0, 1, 0, 0}, white[4] = {1, 1, 1, 1}, zero[4] = {0, 0, 0, 0};
        attribute(1, data.normals.data(), data.normals.size() * sizeof(glm::vec3), 3, up);
        attribute(2, data.colours.data(), data.colours.size() * sizeof(glm::vec4), 4, white);
        attribute(3, data.texcoords.data(), data.texcoords.size() * sizeof(glm::vec2), 2, zero);
        if (!data.indices.empty()) {
            glNamedBufferStorage(mesh.buffers[4], static_cast<GLsizeiptr>(data.indices.size() * 4),
                                 data.indices.data(), 0);
            glVertexArrayElementBuffer(mesh.vao, mesh.buffers[4]);
            mesh.indexed = true;
            mesh.count = static_cast<GLsizei>(data.indices.size());
        } else {
            mesh.count = static_cast<GLsizei>(n);
        }
        mesh.mode = data.topology == Topology::triangles ? GL_TRIANGLES
                    : data.topology == Topology::lines   ? GL_LINES
                                                         : GL_POINTS;
        const std::uint32_t id = next_id_++;
        meshes_[id] = mesh;
        return MeshHandle{id};
    }

    TextureHandle create_texture(const ImageRgba8& image) override {
        if (image.width <= 0 || image.height <= 0 ||
            image.pixels.size() != static_cast<std::size_t>(image.width) * image.height * 4) {
            throw std::invalid_argument("texture size does not match its pixel data");
        }
        GLuint tex = 0;
        glCreateTextures(GL_TEXTURE_2D, 1, &tex);
        glTextureStorage2D(tex, 1, GL_RGBA8, image.width, image.height);
        glTextureSubImage2D(tex, 0, 0, 0, image.width, image.height, GL_RGBA, GL_UNSIGNED_BYTE,
                            image.pixels.data());
        glTextureParameteri(tex, GL_TEXTURE_MIN_FILTER, GL_LINEAR);
        glTextureParameteri(tex, GL_TEXTURE_MAG_FILTER, GL_LINEAR);
        const std::uint32_t id = next_id_++;
        textures_[id] = tex;
        return TextureHandle{id};
    }

    void destroy_texture(TextureHandle handle) override {
        auto it = textures_.find(handle.id);
        if (it == textures_.end()) return;
        glDeleteTextures(1, &it->second);
        textures_.erase(it);
    }

    void destroy_mesh(MeshHandle handle) override {
        auto it = meshes_.find(handle.id);
        if (it == meshes_.end()) return;
        release(it->second);
        meshes_.erase(it);
    }

    void begin_frame(const FrameSetup& setup) override {
        if (setup.width_px <= 0 || setup.height_px <= 0)
            throw std::invalid_argument("frame size must be positive");
        GLint max_size = 0;
        glGetIntegerv(GL_MAX_RENDERBUFFER_SIZE, &max_size);
        if (setup.width_px > max_size || setup.height_px > max_size)
            throw std::runtime_error(
                "frame " + std::to_string(setup.width_px) + "x" + std::to_string(setup.height_px) +
                " exceeds GL_MAX_RENDERBUFFER_SIZE " + std::to_string(max_size));
        const int samples = setup.msaa_samples > 1 ? setup.msaa_samples : 0;
        if (setup.fxaa && samples > 0)
            throw std::invalid_argument("frame setup asks for both MSAA and FXAA");
        fxaa_ = setup.fxaa;
        if (setup.width_px != width_ || setup.height_px != height_ || samples != samples_) {
            release_targets();
            create_targets(setup.width_px, setup.height_px, samples);
        }
        glBindFramebuffer(GL_FRAMEBUFFER, samples_ > 0 ? msaa_fbo_ : resolve_fbo_);
        glViewport(0, 0, width_, height_);
        if (samples_ > 0) {
            glEnable(GL_MULTISAMPLE);
        } else {
            glDisable(GL_MULTISAMPLE);
        }
        glClearColor(setup.clear_colour.r, setup.clear_colour.g, setup.clear_colour.b,
                     setup.clear_colour.a);
        glClearDepth(1.0);
        glDepthMask(GL_TRUE);
        glClear(GL_COLOR_BUFFER_BIT | GL_DEPTH_BUFFER_BIT);
        glEnable(GL_DEPTH_TEST);
        glDepthFunc(GL_LEQUAL);
        glDisable(GL_CULL_FACE);
        glDisable(GL_BLEND);
        glUseProgram(program_);
        const glm::vec3 light = glm::normalize(setup.light_direction);
        glUniform3fv(u_.light_direction, 1, glm::value_ptr(light));
        glUniform1f(u_.ambient, setup.ambient);
        glUniform1i(u_.texture, 0);
    }

    void draw(const DrawCall& call) override {
        auto it = meshes_.find(call.mesh.id);
        if (it == meshes_.end()) throw std::invalid_argument("draw of an unknown mesh handle");
        const GpuMesh& mesh = it->second;
        const glm::mat3 normal_matrix = glm::transpose(glm::inverse(glm::mat3(call.model)));
        glUniformMatrix4fv(u_.model, 1, GL_FALSE, glm::value_ptr(call.model));
        glUniformMatrix4fv(u_.view_projection, 1, GL_FALSE, glm::value_ptr(call.view_projection));
        glUniformMatrix3fv(u_.normal_matrix, 1, GL_FALSE, glm::value_ptr(normal_matrix));
        glUniform4fv(u_.colour, 1, glm::value_ptr(call.colour));
        glUniform1i(u_.lit, call.lit ? 1 : 0);
        glUniform1i(u_.vertex_colour, call.vertex_colour ? 1 : 0);
        glUniform1f(u_.point_size, call.point_size_px);
        glUniform1i(u_.procedural, call.procedural ? 1 : 0);
        auto tex = textures_.find(call.texture.id);
        const bool textured = tex != textures_.end();
        glUniform1i(u_.textured, textured ? 1 : 0);
        if (textured) glBindTextureUnit(0, tex->second);
        glBindVertexArray(mesh.vao);
        if (mesh.indexed) {
            glDrawElements(mesh.mode, mesh.count, GL_UNSIGNED_INT, nullptr);
        } else {
            glDrawArrays(mesh.mode, 0, mesh.count);
        }
    }

    void end_frame() override {
        if (samples_ > 0) {
            glBlitNamedFramebuffer(msaa_fbo_, resolve_fbo_, 0, 0, width_, height_, 0, 0, width_,
                                   height_, GL_COLOR_BUFFER_BIT, GL_NEAREST);
        }
        output_fbo_ = resolve_fbo_;
        if (fxaa_) {
            if (fxaa_fbo_ == 0) create_fxaa_target();
            glBindFramebuffer(GL_FRAMEBUFFER, fxaa_fbo_);
            glBindTextureUnit(0, resolve_colour_);
            glBindVertexArray(empty_vao_);
            glDepthFunc(GL_ALWAYS);
            glUseProgram(fxaa_mark_program_);
            glDrawArrays(GL_TRIANGLES, 0, 3);
            glDepthFunc(GL_EQUAL);
            glDepthMask(GL_FALSE);
            glUseProgram(fxaa_blend_program_);
            glDrawArrays(GL_TRIANGLES, 0, 3);
            glDepthMask(GL_TRUE);
            glBindTextureUnit(0, 0);
            output_fbo_ = fxaa_fbo_;
        }
        const GLenum err = glGetError();
        if (err != GL_NO_ERROR) throw std::runtime_error("GL error " + std::to_string(err));
    }

    ImageRgba8 read_pixels() override {
        ImageRgba8 image;
        image.width = width_;
        image.height = height_;
        const std::size_t row = static_cast<std::size_t>(width_) * 4;
        image.pixels.resize(row * height_);
        glBindFramebuffer(GL_READ_FRAMEBUFFER, output_fbo_);
        glPixelStorei(GL_PACK_ALIGNMENT, 1);
        glReadPixels(0, 0, width_, height_, GL_RGBA, GL_UNSIGNED_BYTE, image.pixels.data());
        // GL rows run bottom to top; images run top to bottom.
        for (int y = 0; y < height_ / 2; ++y) {
            std::swap_ranges(
                image.pixels.begin() + static_cast<std::ptrdiff_t>(y * row),
                image.pixels.begin() + static_cast<std::ptrdiff_t>((y + 1) * row),
                image.pixels.begin() + static_cast<std::ptrdiff_t>((height_ - 1 - y) * row));
        }
        return image;
    }

    std::vector<float> read_depth() override {
        if (samples_ > 0) throw std::logic_error("depth readback needs a frame without MSAA");
        const std::size_t w = static_cast<std::size_t>(width_);
        std::vector<float> depth(w * height_);
        glBindFramebuffer(GL_READ_FRAMEBUFFER, resolve_fbo_);
        glPixelStorei(GL_PACK_ALIGNMENT, 4);
        glReadPixels(0, 0, width_, height_, GL_DEPTH_COMPONENT, GL_FLOAT, depth.data());
        for (int y = 0; y < height_ / 2; ++y) {
            std::swap_ranges(depth.begin() + static_cast<std::ptrdiff_t>(y * w),
                             depth.begin() + static_cast<std::ptrdiff_t>((y + 1) * w),
                             depth.begin() + static_cast<std::ptrdiff_t>((height_ - 1 - y) * w));
        }
        const GLenum err = glGetError();
        if (err != GL_NO_ERROR)
            throw std::runtime_error("GL error " + std::to_string(err) + " reading depth");
        return depth;
    }

  private:
    static void release(GpuMesh& mesh) {
        glDeleteBuffers(5, mesh.buffers);
        glDeleteVertexArrays(1, &mesh.vao);
    }

    void create_targets(int width, int height, int samples) {
        width_ = width;
        height_ = height;
        samples_ = samples;
        // The single-sample colour is a texture, so the FXAA pass can sample it.
        glCreateTextures(GL_TEXTURE_2D, 1, &resolve_colour_);
        glTextureStorage2D(resolve_colour_, 1, GL_RGBA8, width, height);
        glTextureParameteri(resolve_colour_, GL_TEXTURE_MIN_FILTER, GL_LINEAR);
        glTextureParameteri(resolve_colour_, GL_TEXTURE_MAG_FILTER, GL_LINEAR);
        glTextureParameteri(resolve_colour_, GL_TEXTURE_WRAP_S, GL_CLAMP_TO_EDGE);
        glTextureParameteri(resolve_colour_, GL_TEXTURE_WRAP_T, GL_CLAMP_TO_EDGE);
        glCreateRenderbuffers(1, &resolve_depth_);
        glNamedRenderbufferStorage(resolve_depth_, GL_DEPTH_COMPONENT24, width, height);
        glCreateFramebuffers(1, &resolve_fbo_);
        glNamedFramebufferTexture(resolve_fbo_, GL_COLOR_ATTACHMENT0, resolve_colour_, 0);
        glNamedFramebufferRenderbuffer(resolve_fbo_, GL_DEPTH_ATTACHMENT, GL_RENDERBUFFER,
                                       resolve_depth_);
        check_complete(resolve_fbo_);
        if (samples > 0) {
            msaa_fbo_ = renderbuffer_target(msaa_rb_, samples, width, height);
        }
    }

    /// The FXAA passes' colour and edge marks (depth), made on the first FXAA frame of a size.
    void create_fxaa_target() { fxaa_fbo_ = renderbuffer_target(fxaa_rb_, 0, width_, height_); }

    /// A framebuffer of an RGBA8 colour renderbuffer rb[0] and a 24-bit depth renderbuffer
    /// rb[1], multisampled when samples > 0 (0 is plain storage in GL 4.5).
    static GLuint renderbuffer_target(GLuint (&rb)[2], int samples, int width, int height) {
        glCreateRenderbuffers(2, rb);
        glNamedRenderbufferStorageMultisample(rb[0], samples, GL_RGBA8, width, height);
        glNamedRenderbufferStorageMultisample(rb[1], samples, GL_DEPTH_COMPONENT24, width, height);
        GLuint fbo = 0;
        glCreateFramebuffers(1, &fbo);
        glNamedFramebufferRenderbuffer(fbo, GL_COLOR_ATTACHMENT0, GL_RENDERBUFFER, rb[0]);
        glNamedFramebufferRenderbuffer(fbo, GL_DEPTH_ATTACHMENT, GL_RENDERBUFFER, rb[1]);
        check_complete(fbo);
        return fbo;
    }

    static void check_complete(GLuint fbo) {
        const GLenum status = glCheckNamedFramebufferStatus(fbo, GL_FRAMEBUFFER);
        if (status != GL_FRAMEBUFFER_COMPLETE)
            throw std::runtime_error("GL framebuffer incomplete: status " + std::to_string(status));
    }

    void release_targets() {
        const GLuint fbos[3] = {resolve_fbo_, msaa_fbo_, fxaa_fbo_};
        glDeleteFramebuffers(3, fbos);
        glDeleteTextures(1, &resolve_colour_);
        const GLuint renderbuffers[5] = {resolve_depth_, fxaa_rb_[0], fxaa_rb_[1], msaa_rb_[0],
                                         msaa_rb_[1]};
        glDeleteRenderbuffers(5, renderbuffers);
        resolve_fbo_ = msaa_fbo_ = fxaa_fbo_ = output_fbo_ = 0;
        resolve_colour_ = resolve_depth_ = 0;
        fxaa_rb_[0] = fxaa_rb_[1] = msaa_rb_[0] = msaa_rb_[1] = 0;
        width_ = height_ = samples_ = 0;
    }

    GLuint program_ = 0;
    GLuint fxaa_mark_program_ = 0, fxaa_blend_program_ = 0;
    GLuint empty_vao_ = 0;  ///< the FXAA pass's triangle needs a vertex array, not its buffers
    /// Uniform locations of the one program.
    struct Uniforms {
        GLint model, view_projection, normal_matrix, point_size, colour, lit, vertex_colour,
            textured, texture, light_direction, ambient, procedural;
    };
    Uniforms u_{};
    std::unordered_map<std::uint32_t, GpuMesh> meshes_;
    std::unordered_map<std::uint32_t, GLuint> textures_;
    std::uint32_t next_id_ = 1;
    GLuint resolve_fbo_ = 0, msaa_fbo_ = 0, fxaa_fbo_ = 0;
    GLuint output_fbo_ = 0;  ///< where the last frame's colour is: resolve_fbo_ or fxaa_fbo_
    GLuint resolve_colour_ = 0, resolve_depth_ = 0;
    GLuint fxaa_rb_[2] = {}, msaa_rb_[2] = {};
    int width_ = 0, height_ = 0, samples_ = 0;
    bool fxaa_ = false;  ///< this frame ends with the FXAA pass
};

}  // namespace

std::unique_ptr<Device> make_gl_device() { return std::make_unique<GlDevice>(); }

}  // namespace scene_viewer
