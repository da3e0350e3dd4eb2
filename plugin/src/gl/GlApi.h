// The one place that includes the GL/EGL loader (libepoxy). Every GL or EGL call in the project goes through a
// file that includes this header; public headers never do.
#pragma once

#include <epoxy/egl.h>
#include <epoxy/gl.h>

#include <string>

namespace cullide::gl {

/// Throws std::runtime_error naming `what` when a GL error is pending (all builds: the checks are cheap, once per
/// pass). In debug builds a KHR_debug callback also reports messages as they happen.
void checkGlError(const char* what);

/// Embedded shader sources (generated from shaders/ at build time); nullptr for an unknown name.
const char* shaderSource(const char* name);

}  // namespace cullide::gl
