// Diagnoses the EGL client of a GPU machine: client extensions, devices, displays, contexts (with EGL_KHR_debug
// messages). Built into the GPU bundle; run by run.sh when the probe finds no hardware device.
#include <EGL/egl.h>
#include <EGL/eglext.h>
#include <dlfcn.h>
#include <stdio.h>
#include <string.h>

static void* egl;
static void* sym(const char* n) {
    void* p = dlsym(egl, n);
    if (!p) {
        PFNEGLGETPROCADDRESSPROC gpa = (PFNEGLGETPROCADDRESSPROC)dlsym(egl, "eglGetProcAddress");
        if (gpa) p = (void*)gpa(n);
    }
    return p;
}
static void EGLAPIENTRY debugCb(EGLenum error, const char* command, EGLint type, EGLLabelKHR tl, EGLLabelKHR ol,
                                const char* message) {
    (void)tl; (void)ol;
    printf("  [EGL debug] error 0x%x in %s (type 0x%x): %s\n", error, command ? command : "?", type,
           message ? message : "");
}

int main(int argc, char** argv) {
    const char* lib = argc > 1 ? argv[1] : "libEGL.so.1";
    egl = dlopen(lib, RTLD_NOW | RTLD_GLOBAL);
    if (!egl) { printf("dlopen %s: %s\n", lib, dlerror()); return 1; }
    PFNEGLDEBUGMESSAGECONTROLKHRPROC dbg = (PFNEGLDEBUGMESSAGECONTROLKHRPROC)sym("eglDebugMessageControlKHR");
    if (dbg) {
        EGLAttrib attrs[] = {EGL_DEBUG_MSG_CRITICAL_KHR, EGL_TRUE, EGL_DEBUG_MSG_ERROR_KHR, EGL_TRUE,
                             EGL_DEBUG_MSG_WARN_KHR, EGL_TRUE, EGL_DEBUG_MSG_INFO_KHR, EGL_TRUE, EGL_NONE};
        printf("eglDebugMessageControlKHR: %d\n", dbg(debugCb, attrs));
    }
    PFNEGLQUERYSTRINGPROC qs = (PFNEGLQUERYSTRINGPROC)sym("eglQueryString");
    PFNEGLGETERRORPROC err = (PFNEGLGETERRORPROC)sym("eglGetError");
    const char* ce = qs(EGL_NO_DISPLAY, EGL_EXTENSIONS);
    printf("client extensions: %s (error 0x%x)\n", ce ? ce : "(null)", err());
    PFNEGLQUERYDEVICESEXTPROC qd = (PFNEGLQUERYDEVICESEXTPROC)sym("eglQueryDevicesEXT");
    PFNEGLQUERYDEVICESTRINGEXTPROC qds = (PFNEGLQUERYDEVICESTRINGEXTPROC)sym("eglQueryDeviceStringEXT");
    PFNEGLGETPLATFORMDISPLAYEXTPROC gpd = (PFNEGLGETPLATFORMDISPLAYEXTPROC)sym("eglGetPlatformDisplayEXT");
    PFNEGLINITIALIZEPROC init = (PFNEGLINITIALIZEPROC)sym("eglInitialize");
    PFNEGLBINDAPIPROC bind = (PFNEGLBINDAPIPROC)sym("eglBindAPI");
    PFNEGLCREATECONTEXTPROC cc = (PFNEGLCREATECONTEXTPROC)sym("eglCreateContext");
    PFNEGLMAKECURRENTPROC mc = (PFNEGLMAKECURRENTPROC)sym("eglMakeCurrent");
    PFNEGLGETDISPLAYPROC gd = (PFNEGLGETDISPLAYPROC)sym("eglGetDisplay");
    EGLDeviceEXT devs[16];
    EGLint n = 0;
    if (qd) printf("eglQueryDevicesEXT: %d, %d devices (error 0x%x)\n", qd(16, devs, &n), n, err());
    EGLDisplay displays[18];
    int nd = 0;
    for (int i = 0; i < n; ++i) {
        const char* e = qds(devs[i], EGL_EXTENSIONS);
        printf("device %d extensions: %s\n", i, e ? e : "(null)");
        displays[nd++] = gpd ? gpd(EGL_PLATFORM_DEVICE_EXT, devs[i], NULL) : EGL_NO_DISPLAY;
    }
    if (gd) displays[nd++] = gd(EGL_DEFAULT_DISPLAY);
    for (int i = 0; i < nd; ++i) {
        EGLint ma = 0, mi = 0;
        EGLDisplay d = displays[i];
        printf("display %d (%s): %p\n", i, i < n ? "device" : "default", d);
        if (d == EGL_NO_DISPLAY) continue;
        EGLBoolean ok = init(d, &ma, &mi);
        printf("  eglInitialize: %d %d.%d (error 0x%x)\n", ok, ma, mi, err());
        if (!ok) continue;
        const char* v = qs(d, EGL_VENDOR);
        const char* de = qs(d, EGL_EXTENSIONS);
        printf("  vendor %s\n  extensions %s\n", v ? v : "?", de ? de : "?");
        printf("  bind GL: %d\n", bind(EGL_OPENGL_API));
        const EGLint a[] = {EGL_CONTEXT_MAJOR_VERSION, 4, EGL_CONTEXT_MINOR_VERSION, 5,
                            EGL_CONTEXT_OPENGL_PROFILE_MASK, EGL_CONTEXT_OPENGL_CORE_PROFILE_BIT, EGL_NONE};
        EGLContext c = cc(d, (EGLConfig)0, EGL_NO_CONTEXT, a);
        printf("  context %p (error 0x%x)\n", c, err());
        if (c == EGL_NO_CONTEXT) continue;
        printf("  makeCurrent %d (error 0x%x)\n", mc(d, EGL_NO_SURFACE, EGL_NO_SURFACE, c), err());
        const unsigned char* (*gs)(unsigned) = (const unsigned char* (*)(unsigned))sym("glGetString");
        if (gs) printf("  GL_RENDERER %s | %s\n", gs(0x1F01), gs(0x1F02));
    }
    return 0;
}
