#pragma once
/// Headless OpenGL 4.5 core context through EGL (DESIGN.md §5). The EGL device platform
/// (EGL_EXT_platform_device) is tried first so that a machine with a GPU driver uses its GPU;
/// otherwise Mesa's surfaceless platform (EGL_MESA_platform_surfaceless, llvmpipe on machines
/// without a GPU). libepoxy resolves the GL entry points.
///
/// One context per process, created on first use and made current on the calling thread. GL is
/// single-threaded here: every gpu/ function that needs a context must be called from one
/// thread at a time (they call gpu::context() themselves).

#include <string>

namespace scatterlab::gpu {

/// What the context runs on.
struct DeviceInfo {
  std::string vendor;     ///< GL_VENDOR
  std::string renderer;   ///< GL_RENDERER, e.g. "llvmpipe (LLVM 15.0.6, 256 bits)"
  std::string version;    ///< GL_VERSION
  std::string glsl;       ///< GL_SHADING_LANGUAGE_VERSION
  std::string platform;   ///< "device" (EGL_EXT_platform_device) or "surfaceless"
  std::string eglVendor;  ///< EGL_VENDOR of the display used
  /// True when the renderer is a real GPU, not a software rasteriser (llvmpipe, softpipe,
  /// swrast, lavapipe). `--backend auto` picks the GPU only then.
  bool hardware = false;
};

/// The process-wide context. Creates it on the first call and makes it current on the calling
/// thread. Throws GpuError (with what was tried and why it failed) when no OpenGL 4.5 core
/// context can be made; later calls rethrow the same error without trying again.
class Context {
 public:
  const DeviceInfo& info() const { return info_; }
  /// True when this build was compiled with KHR_debug output enabled (debug builds).
  bool debugOutput() const { return debug_; }

 private:
  friend Context& context();
  Context();
  DeviceInfo info_;
  bool debug_ = false;
};

/// Returns the context, current on this thread. Throws GpuError when unavailable.
Context& context();

/// Like context() but never throws: returns nullptr and stores the reason in `why`.
/// Needs no context beforehand (it is how callers ask whether one can be made).
Context* tryContext(std::string* why = nullptr);

/// For an engine (issue 34): scatterlab's context is created on the display of the EGL context
/// current on the calling thread and in its share group, so textures and buffers scatterlab
/// makes (RenderResult::deviceImage) are names in the caller's context too. Call it with the
/// engine's desktop-OpenGL context current, before anything of scatterlab uses the GPU; throws
/// GpuError when no context is current or scatterlab's exists already unshared.
void shareWithCurrentContext();
/// Whether scatterlab's context exists and shares objects with the caller's.
bool sharesWithCaller();

/// Scope guard at the API's edge (Renderer): when a context that is not scatterlab's is current
/// on entry (an engine's), scatterlab's is made current for the scope (so no GL call of ours,
/// object deletion included, lands in the caller's context) and the caller's (display,
/// surfaces, context) is current again at the end; with a shared context, the caller's context
/// then waits on the GPU for scatterlab's commands (a fence and glWaitSync: no host wait), so
/// it sees the image.
///
/// Threads (issue 37): an EGL context is current on one thread at a time, and a Renderer made in
/// one thread and rendered in another aborted the process (libepoxy: no current context, while
/// a GpuFrame deleted its objects). So the guards of all threads take one process-wide lock for
/// their scope (GPU work through the API is serialised), scatterlab's context is made current on
/// the guard's thread at the start, and the outermost guard of a thread leaves it current on no
/// thread at the end (after a glFlush), free for the next thread. Never throws: where the context
/// cannot be made current (another thread uses gpu/ directly), context() says so in a GpuError,
/// and GL objects that die without a current context are left to the driver, not deleted.
class CallerContextGuard {
 public:
  CallerContextGuard();
  ~CallerContextGuard();
  CallerContextGuard(const CallerContextGuard&) = delete;
  CallerContextGuard& operator=(const CallerContextGuard&) = delete;

 private:
  void* display_ = nullptr;
  void* context_ = nullptr;
  void* draw_ = nullptr;
  void* read_ = nullptr;
  bool foreign_ = false;
  bool outermost_ = false;
};

/// Whether a GL context is current on this thread (GL calls without one abort in libepoxy).
bool glContextCurrent();

}  // namespace scatterlab::gpu
