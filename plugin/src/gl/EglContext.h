// Headless OpenGL 4.5 core context through EGL without a window system.
#pragma once

#include "gl/GlApi.h"

#include <memory>
#include <string>

namespace cullide::gl {

/// Owns an EGL display + context made current on the calling thread. Device choice: the EGL device platform
/// (a hardware device first, else Mesa's software device), then Mesa's surfaceless platform. Throws
/// cullide::GlUnavailableError naming what is missing and the Debian package that provides it.
/// Whether `preference` (as EglContext's) selects a hardware EGL device, by device enumeration alone (no display,
/// no context). The environment variable is read when `preference` is empty.
bool hardwareDeviceSelected(const std::string& preference);

class EglContext {
public:
    /// `preference`: "" (env CULLIDE_GL_DEVICE, else automatic), "hardware", "software", "surfaceless", or a device
    /// index ("0", "1", ...).
    explicit EglContext(const std::string& preference);
    ~EglContext();
    EglContext(const EglContext&) = delete;
    EglContext& operator=(const EglContext&) = delete;

    /// Makes the context current on the calling thread (cheap when it already is).
    void makeCurrent();
    /// The same without throwing (destructors): false when the context cannot be made current.
    bool tryMakeCurrent() noexcept;
    /// Releases the context from the calling thread (if current there), so that another thread may make it
    /// current: a culler may be made on one thread and used on another, one thread at a time.
    void release() noexcept;
    const std::string& device() const { return m_device; }
    const std::string& renderer() const { return m_renderer; }
    bool hasTimerQueries() const { return m_timerQueries; }
    /// A CPU rasterizer (llvmpipe, softpipe): GPU levels cost more than they save there.
    bool isSoftware() const { return m_software; }

private:
    bool tryDisplay(EGLDisplay display, const std::string& description, std::string& whyNot);

    EGLDisplay m_display = EGL_NO_DISPLAY;
    EGLContext m_context = EGL_NO_CONTEXT;
    std::string m_device;
    std::string m_renderer;
    bool m_timerQueries = false;
    bool m_software = false;
};

}  // namespace cullide::gl
