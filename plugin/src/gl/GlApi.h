// The one place that includes the GL/EGL loader (libepoxy). Every GL or EGL call in the project goes through a
// file that includes this header; public headers never do.
#pragma once

#include <epoxy/egl.h>
#include <epoxy/gl.h>

#include "PruningBackend.h"

#include <stdexcept>
#include <string>

namespace cullide::gl {

/// A GL error raised while the culler was working (the GL context may still be usable).
class GlError : public BackendError {
public:
    using BackendError::BackendError;
};

/// Throws GlError naming `what` when a GL error is pending (all builds: the checks are cheap, once per pass). In
/// debug builds a KHR_debug callback also reports messages as they happen.
/// Fault injection for tests: while the environment variable CULLIDE_INJECT_GL_ERROR holds a non-empty substring
/// of `what`, the check reports GL_INVALID_OPERATION, as a driver error in the middle of a frame would.
void checkGlError(const char* what);

}  // namespace cullide::gl
