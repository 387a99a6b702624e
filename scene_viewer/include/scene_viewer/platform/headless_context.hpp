#pragma once

/// A headless OpenGL 4.5 core context on EGL, without X or a window: the EGL device platform
/// when a hardware device is present, else Mesa's surfaceless platform (llvmpipe on CPU-only
/// machines). Rendering goes to framebuffer objects (see the GL backend).

#include <memory>
#include <string>

namespace scene_viewer {

/// What the context runs on, from glGetString and EGL.
struct GlInfo {
    std::string vendor;
    std::string renderer;
    std::string version;
    std::string egl_platform;  ///< "device" or "surfaceless"
};

class HeadlessContext {
  public:
    /// Creates and makes current a GL 4.5 core context; throws std::runtime_error naming what is
    /// missing (EGL extension, platform, context version) when EGL cannot start.
    HeadlessContext();
    ~HeadlessContext();
    HeadlessContext(const HeadlessContext&) = delete;
    HeadlessContext& operator=(const HeadlessContext&) = delete;

    GlInfo info() const;

  private:
    struct Impl;
    std::unique_ptr<Impl> impl_;
};

}  // namespace scene_viewer
