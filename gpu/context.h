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

}  // namespace scatterlab::gpu
