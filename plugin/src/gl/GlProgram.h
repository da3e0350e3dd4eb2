// Shader programs from the embedded GLSL sources, and the scoped LeakSanitizer exemption for Mesa's draw path:
// shared by the visibility pass and the snapshot renderer.
#pragma once

#include "gl/GlApi.h"
#include "gl/ShaderPrograms.h"

#if defined(__SANITIZE_ADDRESS__)
#include <sanitizer/lsan_interface.h>
#endif

namespace cullide::gl {

/// Compiles the program's shaders (ShaderPrograms.h) and links them. Throws std::runtime_error with the compiler's or
/// the linker's log (and std::logic_error for a source that was not embedded).
GLuint linkProgram(Program program);

#if defined(__SANITIZE_ADDRESS__)
/// Mesa 22.3's llvmpipe draw path loses 112 bytes (two 56-byte callocs inside swrast_dri, from JIT-compiled code)
/// on the first raster draw or MSAA resolve of a process (valgrind: "definitely lost ... by glDrawArrays"). Mesa is
/// built without frame pointers, so LeakSanitizer cannot attribute it and no suppression matches: allocations
/// inside this scope only are ignored, and it wraps nothing but GL draw calls.
struct ThirdPartyLeakScope {
    ThirdPartyLeakScope() { __lsan_disable(); }
    ~ThirdPartyLeakScope() { __lsan_enable(); }
    ThirdPartyLeakScope(const ThirdPartyLeakScope&) = delete;
    ThirdPartyLeakScope& operator=(const ThirdPartyLeakScope&) = delete;
};
#else
struct ThirdPartyLeakScope {
    ThirdPartyLeakScope() {}  // user-provided: no unused-variable warning at the use site
};
#endif

}  // namespace cullide::gl
