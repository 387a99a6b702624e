#include "scene_viewer/platform/headless_context.hpp"

#include <cstring>
#include <stdexcept>
#include <string>
#include <vector>

#include <EGL/egl.h>
#include <EGL/eglext.h>
#define GL_GLEXT_PROTOTYPES
#include <GL/gl.h>

namespace scene_viewer {

namespace {

bool has_extension(const char* list, const char* name) {
    if (list == nullptr) return false;
    const std::size_t n = std::strlen(name);
    for (const char* p = list; (p = std::strstr(p, name)) != nullptr; p += n) {
        if ((p == list || p[-1] == ' ') && (p[n] == ' ' || p[n] == '\0')) return true;
    }
    return false;
}

std::string egl_error_name(EGLint code) {
    switch (code) {
        case EGL_NOT_INITIALIZED:
            return "EGL_NOT_INITIALIZED";
        case EGL_BAD_ACCESS:
            return "EGL_BAD_ACCESS";
        case EGL_BAD_ALLOC:
            return "EGL_BAD_ALLOC";
        case EGL_BAD_ATTRIBUTE:
            return "EGL_BAD_ATTRIBUTE";
        case EGL_BAD_CONFIG:
            return "EGL_BAD_CONFIG";
        case EGL_BAD_CONTEXT:
            return "EGL_BAD_CONTEXT";
        case EGL_BAD_DISPLAY:
            return "EGL_BAD_DISPLAY";
        case EGL_BAD_MATCH:
            return "EGL_BAD_MATCH";
        case EGL_BAD_PARAMETER:
            return "EGL_BAD_PARAMETER";
        default:
            return "EGL error " + std::to_string(code);
    }
}

/// A display on the first hardware EGL device, or EGL_NO_DISPLAY.
EGLDisplay hardware_device_display(PFNEGLGETPLATFORMDISPLAYEXTPROC get_platform_display) {
    const char* client = eglQueryString(EGL_NO_DISPLAY, EGL_EXTENSIONS);
    if (!has_extension(client, "EGL_EXT_platform_device")) return EGL_NO_DISPLAY;
    auto query_devices =
        reinterpret_cast<PFNEGLQUERYDEVICESEXTPROC>(eglGetProcAddress("eglQueryDevicesEXT"));
    auto query_device_string = reinterpret_cast<PFNEGLQUERYDEVICESTRINGEXTPROC>(
        eglGetProcAddress("eglQueryDeviceStringEXT"));
    if (query_devices == nullptr || query_device_string == nullptr) return EGL_NO_DISPLAY;
    EGLint count = 0;
    if (!query_devices(0, nullptr, &count) || count <= 0) return EGL_NO_DISPLAY;
    std::vector<EGLDeviceEXT> devices(static_cast<std::size_t>(count));
    if (!query_devices(count, devices.data(), &count)) return EGL_NO_DISPLAY;
    for (EGLint i = 0; i < count; ++i) {
        const char* ext = query_device_string(devices[static_cast<std::size_t>(i)], EGL_EXTENSIONS);
        // Mesa lists its software rasteriser as a device too; that is what surfaceless gives.
        if (has_extension(ext, "EGL_MESA_device_software")) continue;
        EGLDisplay d = get_platform_display(EGL_PLATFORM_DEVICE_EXT,
                                            devices[static_cast<std::size_t>(i)], nullptr);
        if (d == EGL_NO_DISPLAY) continue;
        EGLint major = 0, minor = 0;
        if (eglInitialize(d, &major, &minor)) return d;
    }
    return EGL_NO_DISPLAY;
}

}  // namespace

struct HeadlessContext::Impl {
    EGLDisplay display = EGL_NO_DISPLAY;
    EGLContext context = EGL_NO_CONTEXT;
    std::string platform;
};

HeadlessContext::HeadlessContext() : impl_(std::make_unique<Impl>()) {
    const char* client = eglQueryString(EGL_NO_DISPLAY, EGL_EXTENSIONS);
    if (client == nullptr) {
        throw std::runtime_error(
            "EGL client extensions unavailable (is libEGL from GLVND and "
            "libegl-mesa0 installed?)");
    }
    auto get_platform_display = reinterpret_cast<PFNEGLGETPLATFORMDISPLAYEXTPROC>(
        eglGetProcAddress("eglGetPlatformDisplayEXT"));
    if (!has_extension(client, "EGL_EXT_platform_base") || get_platform_display == nullptr) {
        throw std::runtime_error(
            "EGL_EXT_platform_base missing from EGL client extensions (no EGL vendor library? "
            "install libegl-mesa0)");
    }

    Impl& s = *impl_;
    s.display = hardware_device_display(get_platform_display);
    s.platform = "device";
    if (s.display == EGL_NO_DISPLAY) {
        if (!has_extension(client, "EGL_MESA_platform_surfaceless")) {
            throw std::runtime_error(
                "no EGL device and EGL_MESA_platform_surfaceless missing (install libegl-mesa0)");
        }
        s.platform = "surfaceless";
        s.display =
            get_platform_display(EGL_PLATFORM_SURFACELESS_MESA, EGL_DEFAULT_DISPLAY, nullptr);
        EGLint major = 0, minor = 0;
        if (s.display == EGL_NO_DISPLAY || !eglInitialize(s.display, &major, &minor)) {
            throw std::runtime_error("cannot initialise the EGL surfaceless display: " +
                                     egl_error_name(eglGetError()));
        }
    }

    const char* display_ext = eglQueryString(s.display, EGL_EXTENSIONS);
    for (const char* needed :
         {"EGL_KHR_no_config_context", "EGL_KHR_surfaceless_context", "EGL_KHR_create_context"}) {
        if (!has_extension(display_ext, needed)) {
            eglTerminate(s.display);
            throw std::runtime_error(std::string(needed) + " missing on the EGL " + s.platform +
                                     " display");
        }
    }
    if (!eglBindAPI(EGL_OPENGL_API)) {
        eglTerminate(s.display);
        throw std::runtime_error("EGL cannot bind the desktop OpenGL API: " +
                                 egl_error_name(eglGetError()));
    }
    const EGLint attributes[] = {EGL_CONTEXT_MAJOR_VERSION,
                                 4,
                                 EGL_CONTEXT_MINOR_VERSION,
                                 5,
                                 EGL_CONTEXT_OPENGL_PROFILE_MASK,
                                 EGL_CONTEXT_OPENGL_CORE_PROFILE_BIT,
                                 EGL_NONE};
    s.context = eglCreateContext(s.display, EGL_NO_CONFIG_KHR, EGL_NO_CONTEXT, attributes);
    if (s.context == EGL_NO_CONTEXT) {
        const EGLint err = eglGetError();
        eglTerminate(s.display);
        throw std::runtime_error("cannot create an OpenGL 4.5 core context on EGL " + s.platform +
                                 ": " + egl_error_name(err));
    }
    if (!eglMakeCurrent(s.display, EGL_NO_SURFACE, EGL_NO_SURFACE, s.context)) {
        const EGLint err = eglGetError();
        eglDestroyContext(s.display, s.context);
        eglTerminate(s.display);
        throw std::runtime_error("cannot make the EGL context current: " + egl_error_name(err));
    }
}

HeadlessContext::~HeadlessContext() {
    if (impl_ && impl_->display != EGL_NO_DISPLAY) {
        eglMakeCurrent(impl_->display, EGL_NO_SURFACE, EGL_NO_SURFACE, EGL_NO_CONTEXT);
        if (impl_->context != EGL_NO_CONTEXT) eglDestroyContext(impl_->display, impl_->context);
        eglTerminate(impl_->display);
    }
}

GlInfo HeadlessContext::info() const {
    auto str = [](GLenum name) {
        const auto* s = reinterpret_cast<const char*>(glGetString(name));
        return std::string(s != nullptr ? s : "?");
    };
    return GlInfo{str(GL_VENDOR), str(GL_RENDERER), str(GL_VERSION), impl_->platform};
}

}  // namespace scene_viewer
