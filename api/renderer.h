#pragma once
/// Renderer: one scene rendered again and again while lights, camera or time change, keeping
/// what does not change (docs/library.md, "What a Renderer reuses").
///
///   scatterlab::Renderer r = scatterlab::Renderer::fromFile("data/scenes/glow.json");
///   for (int f = 0; f < 48; ++f) {
///     r.setTime(f / 24.0);              // light paths, a moving medium
///     r.set("camera.fov_y_deg=35");     // any scene key, as --set
///     scatterlab::writeExr(r.render().image, "frame.exr");
///   }
///
/// Reused between render() calls: the method object with its parsed settings, and for the
/// volume pipelines (per-voxel, gradient, adaptive, ...) the frame: the density volume, on the
/// GPU backend also the GL context and the textures. Rebuilt: the density when the medium
/// changes (a `medium.*` key, or setTime on a medium that moves with time: procedural models
/// with a rate, velocity or wind, .sog sequences); the method (and with it the density) when a
/// `render.*` key changes. The sampler's sample points are kept with the density (a sampler
/// reads only the medium); S and ∇S at them, dynamic sampling's splits and the radiance volume
/// are computed again when what they depend on changed: the lights, the phase function, σt, the
/// objects, or the camera position where S depends on it (an anisotropic phase function, or
/// dynamic sampling, which weighs its error by the transmittance to the camera). So a camera
/// move with an isotropic phase function, or a change of background or image size, costs
/// only the march (stats: "radiance_reused"). The image is marched every render. `exact`
/// marches the kept density volume too.
///
/// Light paths: a light may carry `"path": [{"t": T, "position": [x,y,z]}, ...]` with strictly
/// increasing T; its position at time t is the linear interpolation (held constant before the
/// first and after the last key). Not thread-safe: one Renderer per thread, or a lock around
/// every call (the Python binding's Renderer takes one, python/module.cpp).

#include <filesystem>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "core/animation.h"
#include "core/method.h"
#include "core/scene.h"

namespace scatterlab {

/// For an engine that draws scatterlab's image with its own OpenGL context (issue 34): call with
/// the engine's EGL context (desktop OpenGL, 4.5 core) current on this thread, before anything
/// of scatterlab uses the GPU. scatterlab's context is then made on the same EGL display in the
/// engine context's share group: RenderResult::deviceImage (Renderer::keepImageOnDevice) is a
/// texture name of the engine's context too. Every Renderer call leaves the engine's context
/// current when it returns, and the engine's context waits on the GPU (not the host) for the
/// image (docs/library.md, "Drawing the image in an engine"). Throws GpuError when no context is
/// current, or scatterlab's already exists unshared.
void shareGlContextWithCurrent();

class Renderer {
 public:
  /// A renderer of the scene document `doc` (relative paths resolve from `baseDir`) with
  /// `method` ("" = render.method) on `backend` ("cpu", "gpu" or "auto"), as createMethod.
  /// Parses the scene now: throws ConfigError / IoError as loadScene does. Calls initialize()
  /// itself (the free functions loadScene, parseScene and createMethod need it called first).
  Renderer(Json doc, std::filesystem::path baseDir, std::string method = "",
           std::string backend = "auto");
  /// The scene file `path` with `--set` overrides applied in order.
  static Renderer fromFile(const std::string& path, const std::vector<std::string>& overrides = {},
                           std::string method = "", std::string backend = "auto");
  Renderer(Renderer&&) noexcept;
  Renderer& operator=(Renderer&&) noexcept;
  ~Renderer();

  /// Applies a `--set` assignment ("lights.0.position=[0.5,1,0.5]") to the scene. On error
  /// (bad path or value) throws ConfigError and the renderer keeps its previous scene.
  void set(const std::string& assignment);
  /// Several assignments, applied in order, then the scene parsed once: what an engine that
  /// moves many lights a frame calls (64 light positions on fig3: one set's cost, not 64; bench
  /// BM_RendererSet). All or nothing: on the first error it throws ConfigError and the renderer
  /// keeps its previous scene.
  void setAll(const std::vector<std::string>& assignments);
  /// Typed setters for an engine that moves lights and the camera per frame: the same as
  /// set("lights.<index>=…") and set("camera=…") with the scene format's keys (lightJson,
  /// cameraJson), checked as a scene file is. The light replaces lights[index] whole (a `path`
  /// it had is gone); ConfigError when the scene has no such light, or for a value out of range.
  void setLight(std::size_t index, const Light& light);
  void setCamera(const Camera& camera);
  /// Sets the animation time (default: the document's medium.density.time, else 0).
  void setTime(double t);
  double time() const { return time_; }

  /// Renders the current scene. `progress` may be null. Stats hold "time" and, for volume
  /// pipelines, "density_reused".
  RenderResult render(Progress* progress = nullptr);

  /// Leave the image on the GPU from the next render() on (RenderResult::deviceImage: a GL
  /// texture name in scatterlab's context, valid until the next render), where the method's
  /// integrator can (GPU backend, compute pipeline's view march); `image` is then empty. For an
  /// engine that draws the texture, and for frame times without the read-back.
  void keepImageOnDevice(bool on);
  /// The scene as the next render() will see it.
  const Scene& scene() const { return scene_; }
  /// The scene document (with light paths), after every set().
  const Json& document() const { return doc_; }
  /// The method (created on the first render() after a render.* change).
  Method& method();

 private:
  void rebuild(const Json& doc, double t, bool mediumKept = false);

  Json doc_;
  std::filesystem::path baseDir_;
  std::string methodName_, backend_;
  double time_ = 0.0;
  Scene scene_;
  Json mediumDoc_, objectsDoc_, renderDoc_;  ///< what scene_.medium, .objects, method_ came from
  std::unique_ptr<Method> method_;
  bool imageOnDevice_ = false;
};

}  // namespace scatterlab
