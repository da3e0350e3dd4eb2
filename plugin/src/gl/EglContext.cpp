#include "gl/EglContext.h"

#include "cullide/Culler.h"

#include <dlfcn.h>
#include <link.h>

#include <cstdio>
#include <map>
#include <mutex>
#include <cstdlib>
#include <cstring>
#include <stdexcept>
#include <vector>

namespace cullide::gl {
namespace {

constexpr const char* kPackages = "install libegl1 libegl-mesa0 libgl1-mesa-dri (Mesa llvmpipe) or an NVIDIA driver";

bool hasExtension(const char* list, const char* name) {
    if (list == nullptr) return false;
    const std::size_t n = std::strlen(name);
    for (const char* p = list; (p = std::strstr(p, name)) != nullptr; p += n) {
        if ((p == list || p[-1] == ' ') && (p[n] == ' ' || p[n] == '\0')) return true;
    }
    return false;
}

#ifndef NDEBUG
void GLAPIENTRY debugCallback(GLenum, GLenum type, GLuint, GLenum severity, GLsizei, const GLchar* message,
                              const void*) {
    if (type == GL_DEBUG_TYPE_ERROR || severity == GL_DEBUG_SEVERITY_HIGH)
        std::fprintf(stderr, "cullide: GL debug: %s\n", message);
}
#endif

/// EGL displays are per device and process-wide; eglTerminate would invalidate every context on one. Count the
/// users of each display and terminate it when the last one goes.
std::mutex& displayMutex() {
    static std::mutex m;
    return m;
}
std::map<EGLDisplay, int>& displayUsers() {
    static std::map<EGLDisplay, int> users;
    return users;
}
/// Keeps the GL driver that EGL loaded (Mesa's *_dri.so / libgallium, the vendor's libEGL_*) loaded for the rest of
/// the process (RTLD_NODELETE). Without this, eglTerminate of the last display unloads it: every culler created
/// afterwards (tests, the Bullet adapter's culler re-created for a larger margin) pays for loading and initialising
/// the driver again, and leak checkers cannot name the module of the driver's own allocations (LSan then reports
/// them from an "unknown module" that no suppression matches).
void pinGlDrivers() {
    dl_iterate_phdr(
        [](dl_phdr_info* info, std::size_t, void*) {
            const char* name = info->dlpi_name;
            if (name == nullptr || *name == '\0') return 0;
            const bool driver = std::strstr(name, "_dri.so") != nullptr || std::strstr(name, "libgallium") != nullptr ||
                                std::strstr(name, "libEGL_") != nullptr;
            if (driver) dlopen(name, RTLD_LAZY | RTLD_NOLOAD | RTLD_NODELETE);  // a reference never dropped
            return 0;
        },
        nullptr);
}

/// eglInitialize + one more user, atomically with respect to releaseDisplay's eglTerminate.
bool retainDisplay(EGLDisplay d) {
    std::lock_guard<std::mutex> lock(displayMutex());
    EGLint major = 0;
    EGLint minor = 0;
    if (!eglInitialize(d, &major, &minor)) return false;
    ++displayUsers()[d];
    pinGlDrivers();
    return true;
}
void releaseDisplay(EGLDisplay d) {
    std::lock_guard<std::mutex> lock(displayMutex());
    auto it = displayUsers().find(d);
    if (it == displayUsers().end() || --it->second == 0) {
        if (it != displayUsers().end()) displayUsers().erase(it);
        eglTerminate(d);
    }
}

}  // namespace

void checkGlError(const char* what) {
    GLenum error = glGetError();
    // Drain every pending flag (GL keeps one per kind): a stale one must not fail the next frame's check too.
    for (int k = 0; k < 16 && error != GL_NO_ERROR && glGetError() != GL_NO_ERROR; ++k) {
    }
    if (error == GL_NO_ERROR) {
        const char* inject = std::getenv("CULLIDE_INJECT_GL_ERROR");
        if (inject != nullptr && *inject != '\0' && std::strstr(what, inject) != nullptr) error = GL_INVALID_OPERATION;
    }
    if (error != GL_NO_ERROR) {
        char buffer[160];
        std::snprintf(buffer, sizeof buffer, "OpenGL error 0x%04x after %s", error, what);
        throw GlError(buffer);
    }
}

EglContext::EglContext(const std::string& preferenceArg) {
    std::string preference = preferenceArg;
    if (preference.empty()) {
        if (const char* env = std::getenv("CULLIDE_GL_DEVICE")) preference = env;
    }
    if (!epoxy_has_egl())
        throw GlUnavailableError(std::string("no EGL library found (libEGL.so.1): ") + kPackages);

    const char* clientExtensions = eglQueryString(EGL_NO_DISPLAY, EGL_EXTENSIONS);
    std::string reasons;
    const bool wantSurfaceless = preference == "surfaceless";
    bool matchedDevice = false;

    // Device enumeration: EGL_EXT_device_enumeration, or EGL_EXT_device_base (enumeration and query in one), which
    // is all NVIDIA's EGL offers (driver 580: no separate EGL_EXT_device_enumeration).
    const bool enumeration = hasExtension(clientExtensions, "EGL_EXT_device_enumeration") ||
                             hasExtension(clientExtensions, "EGL_EXT_device_base");
    const bool platformDevice = hasExtension(clientExtensions, "EGL_EXT_platform_device");
    if (!wantSurfaceless && platformDevice && enumeration) {
        EGLint count = 0;
        eglQueryDevicesEXT(0, nullptr, &count);
        std::vector<EGLDeviceEXT> devices(static_cast<std::size_t>(count > 0 ? count : 0));
        if (count > 0) eglQueryDevicesEXT(count, devices.data(), &count);
        // Order: hardware devices first, then software ones, unless the preference says otherwise.
        std::vector<std::pair<EGLDeviceEXT, std::string>> candidates;
        for (int pass = 0; pass < 2; ++pass) {
            for (std::size_t i = 0; i < devices.size(); ++i) {
                const char* extensions = eglQueryDeviceStringEXT(devices[i], EGL_EXTENSIONS);
                const bool software = hasExtension(extensions, "EGL_MESA_device_software");
                if ((pass == 0) == software) continue;
                const std::string index = std::to_string(i);
                if (!preference.empty() && preference != "hardware" && preference != "software" &&
                    preference != index)
                    continue;
                if (preference == "hardware" && software) continue;
                if (preference == "software" && !software) continue;
                const char* drm = hasExtension(extensions, "EGL_EXT_device_drm")
                                      ? eglQueryDeviceStringEXT(devices[i], EGL_DRM_DEVICE_FILE_EXT)
                                      : nullptr;
                candidates.emplace_back(devices[i], "EGL device " + index + (software ? " (software)" : " (hardware)") +
                                                        (drm ? std::string(" ") + drm : std::string()));
            }
        }
        for (const auto& [device, description] : candidates) {
            matchedDevice = true;
            EGLDisplay display = eglGetPlatformDisplayEXT(EGL_PLATFORM_DEVICE_EXT, device, nullptr);
            if (display != EGL_NO_DISPLAY && tryDisplay(display, description, reasons)) return;
        }
    } else if (!wantSurfaceless) {
        reasons += platformDevice ? "the EGL client offers no device enumeration (EGL_EXT_device_enumeration or "
                                    "EGL_EXT_device_base); "
                                  : "EGL_EXT_platform_device is not offered by the EGL client; ";
    }
    const bool allowSurfaceless = preference.empty() || wantSurfaceless || preference == "software";
    if (allowSurfaceless && hasExtension(clientExtensions, "EGL_MESA_platform_surfaceless")) {
        EGLDisplay display = eglGetPlatformDisplayEXT(EGL_PLATFORM_SURFACELESS_MESA, EGL_DEFAULT_DISPLAY, nullptr);
        if (display != EGL_NO_DISPLAY && tryDisplay(display, "Mesa surfaceless platform", reasons)) return;
    }
    if (!preference.empty() && !matchedDevice && !wantSurfaceless)
        reasons += "no EGL device matches CULLIDE_GL_DEVICE/device setting '" + preference + "'; ";
    throw GlUnavailableError("no usable headless OpenGL 4.5 core context: " + reasons + kPackages);
}

bool EglContext::tryDisplay(EGLDisplay display, const std::string& description, std::string& whyNot) {
    if (!retainDisplay(display)) {
        whyNot += description + ": eglInitialize failed; ";
        return false;
    }
    const char* extensions = eglQueryString(display, EGL_EXTENSIONS);
    if (!hasExtension(extensions, "EGL_KHR_surfaceless_context") ||
        !hasExtension(extensions, "EGL_KHR_no_config_context") || !eglBindAPI(EGL_OPENGL_API)) {
        whyNot += description + ": lacks surfaceless/no-config contexts or desktop OpenGL; ";
        releaseDisplay(display);
        return false;
    }
    const EGLint attributes[] = {EGL_CONTEXT_MAJOR_VERSION, 4, EGL_CONTEXT_MINOR_VERSION, 5,
                                 EGL_CONTEXT_OPENGL_PROFILE_MASK, EGL_CONTEXT_OPENGL_CORE_PROFILE_BIT,
#ifndef NDEBUG
                                 EGL_CONTEXT_OPENGL_DEBUG, EGL_TRUE,
#endif
                                 EGL_NONE};
    EGLContext context = eglCreateContext(display, EGL_NO_CONFIG_KHR, EGL_NO_CONTEXT, attributes);
    if (context == EGL_NO_CONTEXT) {
        whyNot += description + ": no OpenGL 4.5 core context; ";
        releaseDisplay(display);
        return false;
    }
    if (!eglMakeCurrent(display, EGL_NO_SURFACE, EGL_NO_SURFACE, context)) {
        whyNot += description + ": eglMakeCurrent failed; ";
        eglDestroyContext(display, context);
        releaseDisplay(display);
        return false;
    }
    m_display = display;
    m_context = context;
    m_device = description;
    const auto* renderer = reinterpret_cast<const char*>(glGetString(GL_RENDERER));
    const auto* version = reinterpret_cast<const char*>(glGetString(GL_VERSION));
    m_renderer = std::string(renderer ? renderer : "?") + " | " + (version ? version : "?");
    const std::string lower = renderer ? renderer : "";
    m_software = lower.find("llvmpipe") != std::string::npos || lower.find("softpipe") != std::string::npos ||
                 lower.find("SwiftShader") != std::string::npos;
    m_timerQueries = epoxy_gl_version() >= 33 || epoxy_has_gl_extension("GL_ARB_timer_query");
#ifndef NDEBUG
    if (epoxy_has_gl_extension("GL_KHR_debug")) {
        glEnable(GL_DEBUG_OUTPUT);
        glDebugMessageCallback(debugCallback, nullptr);
    }
#endif
    return true;
}

bool EglContext::tryMakeCurrent() noexcept {
    return eglGetCurrentContext() == m_context ||
           eglMakeCurrent(m_display, EGL_NO_SURFACE, EGL_NO_SURFACE, m_context) == EGL_TRUE;
}

void EglContext::release() noexcept {
    if (eglGetCurrentContext() == m_context) eglMakeCurrent(m_display, EGL_NO_SURFACE, EGL_NO_SURFACE, EGL_NO_CONTEXT);
}

void EglContext::makeCurrent() {
    if (!tryMakeCurrent()) throw GlUnavailableError("eglMakeCurrent failed for the culler's context");
}

EglContext::~EglContext() {
    if (m_display == EGL_NO_DISPLAY) return;
    if (eglGetCurrentContext() == m_context) eglMakeCurrent(m_display, EGL_NO_SURFACE, EGL_NO_SURFACE, EGL_NO_CONTEXT);
    eglDestroyContext(m_display, m_context);
    releaseDisplay(m_display);
}

bool hardwareDeviceSelected(const std::string& preferenceArg) {
    std::string preference = preferenceArg;
    if (preference.empty()) {
        if (const char* env = std::getenv("CULLIDE_GL_DEVICE")) preference = env;
    }
    if (preference == "software" || preference == "surfaceless" || !epoxy_has_egl()) return false;
    const char* clientExtensions = eglQueryString(EGL_NO_DISPLAY, EGL_EXTENSIONS);
    const bool enumeration = hasExtension(clientExtensions, "EGL_EXT_device_enumeration") ||
                             hasExtension(clientExtensions, "EGL_EXT_device_base");
    if (!enumeration || !hasExtension(clientExtensions, "EGL_EXT_platform_device")) return false;
    EGLint count = 0;
    if (!eglQueryDevicesEXT(0, nullptr, &count) || count <= 0) return false;
    std::vector<EGLDeviceEXT> devices(static_cast<std::size_t>(count));
    if (!eglQueryDevicesEXT(count, devices.data(), &count)) return false;
    for (std::size_t i = 0; i < static_cast<std::size_t>(count); ++i) {
        const bool software =
            hasExtension(eglQueryDeviceStringEXT(devices[i], EGL_EXTENSIONS), "EGL_MESA_device_software");
        if (preference.empty() || preference == "hardware") {
            if (!software) return true;
        } else if (preference == std::to_string(i)) {
            return !software;
        }
    }
    return false;
}

}  // namespace cullide::gl

namespace cullide {

bool hasHardwareGlDevice(const std::string& device) {
    static std::mutex mutex;
    static std::map<std::string, bool> answers;
    const std::lock_guard<std::mutex> lock(mutex);
    const auto it = answers.find(device);
    if (it != answers.end()) return it->second;
    const bool hardware = gl::hardwareDeviceSelected(device);
    answers.emplace(device, hardware);
    return hardware;
}

}  // namespace cullide
