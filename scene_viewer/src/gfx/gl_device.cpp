#include "scene_viewer/gfx/gl_device.hpp"

#include <algorithm>
#include <stdexcept>
#include <string>
#include <unordered_map>

#include <glm/gtc/type_ptr.hpp>

#include "gl_shaders.hpp"

namespace scene_viewer {

namespace {

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
        program_ = link_scene_program();
        try {
            fxaa_mark_program_ = link_fxaa_mark_program();
            fxaa_blend_program_ = link_fxaa_blend_program();
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
                      at("u_light_direction"), at("u_ambient"),         at("u_procedural"),
                      at("u_texture_frame")};
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
        glUniformMatrix4fv(u_.texture_frame, 1, GL_FALSE, glm::value_ptr(setup.texture_frame));
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
            textured, texture, light_direction, ambient, procedural, texture_frame;
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
