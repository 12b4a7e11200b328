#include "gpu/context.h"

#include <epoxy/egl.h>
#include <epoxy/gl.h>

#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <memory>
#include <mutex>
#include <optional>
#include <vector>

#include "core/error.h"
#include "gpu/validate.h"

namespace scatterlab::gpu {

namespace {

struct Egl {
  EGLDisplay display = EGL_NO_DISPLAY;
  EGLContext ctx = EGL_NO_CONTEXT;
  std::string platform;
};

bool hasExtension(const char* list, const char* name) {
  if (!list) return false;
  const size_t n = std::strlen(name);
  for (const char* p = list; (p = std::strstr(p, name)); p += n)
    if ((p == list || p[-1] == ' ') && (p[n] == ' ' || p[n] == '\0')) return true;
  return false;
}

std::string eglErrorName(EGLint e) {
  switch (e) {
    case EGL_SUCCESS:
      return "EGL_SUCCESS";
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
    default: {
      char buf[32];
      std::snprintf(buf, sizeof buf, "EGL error 0x%04x", unsigned(e));
      return buf;
    }
  }
}

/// Initialises `dpy` and creates a 4.5 core context on it (in `share`'s share group when not
/// EGL_NO_CONTEXT); on failure terminates it (unless `borrowed`: a display of the caller's)
/// and appends the reason to `why`.
bool makeContext(EGLDisplay dpy, const std::string& platform, Egl& out, std::string& why,
                 EGLContext share = EGL_NO_CONTEXT, bool borrowed = false) {
  const auto terminate = [&] {
    if (!borrowed) eglTerminate(dpy);
  };
  EGLint major = 0, minor = 0;
  if (!eglInitialize(dpy, &major, &minor)) {
    why += platform + ": eglInitialize failed (" + eglErrorName(eglGetError()) + "); ";
    return false;
  }
  const char* exts = eglQueryString(dpy, EGL_EXTENSIONS);
  if (!eglBindAPI(EGL_OPENGL_API)) {
    why += platform + ": no desktop OpenGL API; ";
    terminate();
    return false;
  }
  EGLConfig config = nullptr;
  const bool noConfig = hasExtension(exts, "EGL_KHR_no_config_context");
  if (!noConfig) {
    const EGLint attrs[] = {EGL_SURFACE_TYPE, EGL_PBUFFER_BIT, EGL_RENDERABLE_TYPE, EGL_OPENGL_BIT,
                            EGL_NONE};
    EGLint n = 0;
    if (!eglChooseConfig(dpy, attrs, &config, 1, &n) || n < 1) {
      why += platform + ": no EGL config for OpenGL; ";
      terminate();
      return false;
    }
  }
#ifndef NDEBUG
  const EGLint debugFlag = EGL_CONTEXT_OPENGL_DEBUG_BIT_KHR;
#else
  const EGLint debugFlag = 0;
#endif
  const EGLint ctxAttrs[] = {EGL_CONTEXT_MAJOR_VERSION,
                             4,
                             EGL_CONTEXT_MINOR_VERSION,
                             5,
                             EGL_CONTEXT_OPENGL_PROFILE_MASK,
                             EGL_CONTEXT_OPENGL_CORE_PROFILE_BIT,
                             EGL_CONTEXT_FLAGS_KHR,
                             debugFlag,
                             EGL_NONE};
  EGLContext ctx = eglCreateContext(dpy, noConfig ? EGL_NO_CONFIG_KHR : config, share, ctxAttrs);
  if (ctx == EGL_NO_CONTEXT) {
    why += platform + ": no OpenGL 4.5 core context (" + eglErrorName(eglGetError()) + "); ";
    terminate();
    return false;
  }
  if (!eglMakeCurrent(dpy, EGL_NO_SURFACE, EGL_NO_SURFACE, ctx)) {
    why += platform + ": eglMakeCurrent without surface failed (" + eglErrorName(eglGetError()) +
           "); ";
    eglDestroyContext(dpy, ctx);
    terminate();
    return false;
  }
  out.display = dpy;
  out.ctx = ctx;
  out.platform = platform;
  return true;
}

std::optional<Egl> createEgl(std::string& why) {
  Egl egl;
  const char* clientExts = eglQueryString(EGL_NO_DISPLAY, EGL_EXTENSIONS);
  if (!clientExts) {
    why = "EGL client extensions unavailable (no EGL 1.5 / EGL_EXT_client_extensions); ";
    return std::nullopt;
  }
  // 1. A GPU through the device platform. Mesa also lists a software device there; prefer
  //    devices that are not software ones by trying them in order and keeping the first
  //    hardware renderer.
  if (hasExtension(clientExts, "EGL_EXT_platform_device") &&
      hasExtension(clientExts, "EGL_EXT_device_enumeration")) {
    EGLint n = 0;
    eglQueryDevicesEXT(0, nullptr, &n);
    std::vector<EGLDeviceEXT> devices(size_t(std::max(n, 0)));
    if (n > 0 && eglQueryDevicesEXT(n, devices.data(), &n)) {
      for (EGLint i = 0; i < n; ++i) {
        const char* dexts = eglQueryDeviceStringEXT(devices[size_t(i)], EGL_EXTENSIONS);
        // Mesa's software device advertises EGL_MESA_device_software; skip it here so the
        // surfaceless path below reports itself honestly.
        if (hasExtension(dexts, "EGL_MESA_device_software")) continue;
        EGLDisplay dpy =
            eglGetPlatformDisplayEXT(EGL_PLATFORM_DEVICE_EXT, devices[size_t(i)], nullptr);
        if (dpy == EGL_NO_DISPLAY) continue;
        if (makeContext(dpy, "device", egl, why)) return egl;
      }
    }
    if (n == 0) why += "device: no EGL devices; ";
  }
  // 2. Mesa's surfaceless platform (llvmpipe without a GPU).
  if (hasExtension(clientExts, "EGL_MESA_platform_surfaceless")) {
    EGLDisplay dpy =
        eglGetPlatformDisplayEXT(EGL_PLATFORM_SURFACELESS_MESA, EGL_DEFAULT_DISPLAY, nullptr);
    if (dpy != EGL_NO_DISPLAY && makeContext(dpy, "surfaceless", egl, why)) return egl;
    if (dpy == EGL_NO_DISPLAY) why += "surfaceless: no display; ";
  } else {
    why += "surfaceless: EGL_MESA_platform_surfaceless not offered; ";
  }
  return std::nullopt;
}

#ifndef NDEBUG
void GLAPIENTRY debugCallback(GLenum, GLenum type, GLuint, GLenum severity, GLsizei,
                              const GLchar* message, const void*) {
  if (severity == GL_DEBUG_SEVERITY_NOTIFICATION) return;
  std::fprintf(stderr, "scatterlab GL debug%s: %s\n", type == GL_DEBUG_TYPE_ERROR ? " (error)" : "",
               message);
}

#endif

std::string glString(GLenum e) {
  const GLubyte* s = glGetString(e);
  return s ? reinterpret_cast<const char*>(s) : "";
}

std::mutex gMutex;
std::unique_ptr<Context> gContext;
std::optional<std::string> gFailure;
Egl gEgl;
/// shareWithCurrentContext(): the caller's display and context to share with.
EGLDisplay gShareDisplay = EGL_NO_DISPLAY;
EGLContext gShareContext = EGL_NO_CONTEXT;

}  // namespace

Context::Context() {
  std::string why;
  if (const char* off = std::getenv("SCATTERLAB_NO_GPU"); off && *off && std::strcmp(off, "0"))
    throw GpuError("no OpenGL context: the GPU backend is disabled by SCATTERLAB_NO_GPU=" +
                   std::string(off) + "; use --backend cpu");
  // Validation checks every shader's compile log for warnings (gpu/gl.cpp, Shader): Mesa's
  // shader cache skips the compile of a text it has seen, log and all, so validation turns the
  // cache off unless the caller set it.
  if (validationRequested()) setenv("MESA_SHADER_CACHE_DISABLE", "true", 0);
  std::optional<Egl> egl;
  if (gShareContext != EGL_NO_CONTEXT) {
    Egl shared;
    if (makeContext(gShareDisplay, "shared with the caller's context", shared, why, gShareContext,
                    true))
      egl = shared;
    else
      throw GpuError("no OpenGL 4.5 core context sharing the caller's EGL context (" + why + ")");
  } else {
    egl = createEgl(why);
  }
  if (!egl) {
    // `why` lists each EGL platform's failure as "platform: reason; ".
    while (!why.empty() && (why.back() == ' ' || why.back() == ';')) why.pop_back();
    throw GpuError("no GPU found: no OpenGL 4.5 core context through EGL (" + why +
                   "); use --backend cpu");
  }
  gEgl = *egl;
  info_.platform = egl->platform;
  const char* ev = eglQueryString(egl->display, EGL_VENDOR);
  info_.eglVendor = ev ? ev : "";
  info_.vendor = glString(GL_VENDOR);
  info_.renderer = glString(GL_RENDERER);
  info_.version = glString(GL_VERSION);
  info_.glsl = glString(GL_SHADING_LANGUAGE_VERSION);
  if (epoxy_gl_version() < 45)
    throw GpuError("OpenGL " + info_.version + " on '" + info_.renderer +
                   "' is older than the 4.5 core the GPU backend needs; use --backend cpu");
  const std::string& r = info_.renderer;
  info_.hardware = r.find("llvmpipe") == std::string::npos &&
                   r.find("softpipe") == std::string::npos &&
                   r.find("swrast") == std::string::npos && r.find("Software") == std::string::npos;
  if (validationRequested()) installValidation();
#ifndef NDEBUG
  if (epoxy_has_gl_extension("GL_KHR_debug") || epoxy_gl_version() >= 43) {
    glEnable(GL_DEBUG_OUTPUT);
    glEnable(GL_DEBUG_OUTPUT_SYNCHRONOUS);
    glDebugMessageCallback(debugCallback, nullptr);
    debug_ = true;
  }
#endif
}

Context& context() {
  std::lock_guard<std::mutex> lock(gMutex);
  if (gFailure) throw GpuError(*gFailure);
  if (!gContext) {
    try {
      gContext.reset(new Context());
    } catch (const GpuError& e) {
      gFailure = e.what();
      throw;
    }
  } else if (eglGetCurrentContext() != gEgl.ctx) {
    if (!eglMakeCurrent(gEgl.display, EGL_NO_SURFACE, EGL_NO_SURFACE, gEgl.ctx))
      throw GpuError("cannot make the GL context current on this thread (" +
                     eglErrorName(eglGetError()) + "); it may be current on another thread");
  }
  return *gContext;
}

void shareWithCurrentContext() {
  std::lock_guard<std::mutex> lock(gMutex);
  const EGLContext current = eglGetCurrentContext();
  if (current == EGL_NO_CONTEXT)
    throw GpuError(
        "shareWithCurrentContext: no EGL context is current on this thread (make the "
        "engine's context current first)");
  if (gContext) {
    if (gShareContext == current) return;  // already shared with it
    throw GpuError(
        "shareWithCurrentContext: scatterlab's GL context exists already and shares nothing "
        "with this one; call it before anything of scatterlab uses the GPU");
  }
  if (eglQueryAPI() != EGL_OPENGL_API)
    throw GpuError("shareWithCurrentContext: the current context is not a desktop OpenGL one");
  gShareDisplay = eglGetCurrentDisplay();
  gShareContext = current;
  gFailure.reset();
}

bool sharesWithCaller() {
  std::lock_guard<std::mutex> lock(gMutex);
  return gContext && gShareContext != EGL_NO_CONTEXT;
}

namespace {
// The API's GPU work, one thread at a time (CallerContextGuard), and each thread's guard depth.
std::recursive_mutex gUse;
thread_local int tGuardDepth = 0;
}  // namespace

bool glContextCurrent() {
  return eglGetCurrentContext() != EGL_NO_CONTEXT;
}

CallerContextGuard::CallerContextGuard() {
  gUse.lock();
  outermost_ = tGuardDepth++ == 0;
  display_ = eglGetCurrentDisplay();
  context_ = eglGetCurrentContext();
  draw_ = eglGetCurrentSurface(EGL_DRAW);
  read_ = eglGetCurrentSurface(EGL_READ);
  std::lock_guard<std::mutex> lock(gMutex);
  // A foreign context is current: scatterlab's (when it exists) becomes current for the work
  // in this scope, so that no GL call of ours (object deletion included) lands in the caller's.
  foreign_ = context_ != EGL_NO_CONTEXT && (!gContext || context_ != gEgl.ctx);
  // Ours, made current on this thread (it may have been left on none by another thread's guard).
  if (gContext && context_ != gEgl.ctx)
    eglMakeCurrent(gEgl.display, EGL_NO_SURFACE, EGL_NO_SURFACE, gEgl.ctx);
}

CallerContextGuard::~CallerContextGuard() {
  {
    std::lock_guard<std::mutex> lock(gMutex);
    const bool oursCurrent = gContext && eglGetCurrentContext() == gEgl.ctx;
    if (foreign_) {
      const bool shared = gShareContext == context_;
      GLsync done = nullptr;
      if (oursCurrent) {
        // The caller's context waits for our commands on the GPU (glWaitSync below), not the
        // host.
        if (shared) done = glFenceSync(GL_SYNC_GPU_COMMANDS_COMPLETE, 0);
        glFlush();
      }
      eglMakeCurrent(display_, draw_, read_, context_);
      if (done) {
        glWaitSync(done, 0, GL_TIMEOUT_IGNORED);
        glDeleteSync(done);  // deleted once no wait refers to it
      }
    } else if (outermost_ && oursCurrent) {
      // Free for the next thread; releasing a context flushes its commands (no host wait).
      glFlush();
      eglMakeCurrent(gEgl.display, EGL_NO_SURFACE, EGL_NO_SURFACE, EGL_NO_CONTEXT);
    }
  }
  --tGuardDepth;
  gUse.unlock();
}

Context* tryContext(std::string* why) {
  try {
    return &context();
  } catch (const GpuError& e) {
    if (why) *why = e.what();
    return nullptr;
  }
}

}  // namespace scatterlab::gpu
