#pragma once
/// Stage interface: a whole rendering method (scene -> image), composed from the other stages
/// or standing alone (the exact reference). Implementations live in cpu/ (CPU) and gpu/.

#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <string_view>

#include "core/image.h"
#include "core/progress.h"
#include "core/registry.h"
#include "core/scene.h"
#include "core/stages.h"
#include "core/stats.h"

namespace scatterlab {

struct RenderResult {
  Image image;
  RenderStats stats;
  /// The radiance samples a sample-based method used (positions, radii, levels, S, ∇S);
  /// empty for methods without samples. For pictures of the sampling and for tests. On the GPU
  /// with Method::imageOnDevice (compute pipeline) the samples stay on the device too: S and
  /// ∇S are not read back (gradient), and `adaptive`'s final samples are not read at all
  /// (empty; stats.samples and the levels' stats are read after the frame).
  std::vector<RadianceSample> samples;
  /// The volumes the method built, for export (`render --density-vdb / --radiance-vdb`) and
  /// tests: the density volume (CPU methods), the source-radiance volume S (CPU methods that
  /// build one; `exact` has none). Null where a method has none or keeps it on the GPU.
  std::shared_ptr<const DensityGrid> density;
  std::shared_ptr<const RadianceGrid> radiance;
  /// With Method::imageOnDevice, where the GPU integrator left the image: an RGBA32F 2D texture
  /// (rgb radiance, a the alpha of `image`), row 0 at the top as in `image`, in scatterlab's GL
  /// context (gpu::context(); share it, or copy the texture, to use it in another context).
  /// Valid until the next render() of the same method. `image` is then empty (0 × 0).
  struct DeviceImage {
    unsigned texture = 0;  ///< the GL texture name
    int width = 0, height = 0;
  };
  std::optional<DeviceImage> deviceImage;
};

class Method {
 public:
  virtual ~Method() = default;
  /// Renders `scene` (whose `render` settings this method was created from). `progress` may be
  /// null. Throws scatterlab::Error on failure, LimitError when the image would hold a NaN or
  /// infinite colour or alpha value (docs/reliability.md). Needs no current GL context (GPU
  /// methods make their own).
  virtual RenderResult render(const Scene& scene, Progress* progress) = 0;

  /// Keys of the render object that only other registered methods read, ignored by this one
  /// (dotted paths, e.g. "render.sampler"); set by createMethod. The tool lists them once on
  /// stderr.
  std::vector<std::string> ignoredKeys;

  /// When true, a volume-pipeline method keeps its frame (density volume, GL context and
  /// textures) between render() calls and skips the density stage while the scene's medium is
  /// the same one (same density model object, box and resolution); stats then hold
  /// "density_reused": true; a sample-based method keeps its sampler's samples with it
  /// ("samples_reused": true; S and ∇S are evaluated anew). Off by default (every render builds its
  /// own volumes); set by scatterlab::Renderer (api/renderer.h). Methods without a density stage
  /// ignore it.
  bool retainDensity = false;
  /// Leave the image on the GPU (RenderResult::deviceImage) instead of reading it back: for an
  /// engine that draws it, or a frame timed without the read-back. Where the integrator cannot
  /// (the CPU backend, the raster slice marcher, the screen-space competitors) the image is
  /// read back as usual and deviceImage stays empty. Needs retainDensity (the texture lives in
  /// the kept frame). The frame then waits for nothing before the image is asked for (issue 33:
  /// stats host_waits); RenderResult::samples says what stays on the device.
  bool imageOnDevice = false;
};

/// A registered method (methods/register.cpp registers each built-in one once).
struct MethodEntry {
  /// One line for listings.
  std::string summary;
  /// The render keys the method reads (top-level names, e.g. "sampler", "delta1"), the same on
  /// every backend; "method" and "backend" are read by createMethod.
  std::vector<std::string> keys;
  /// The rows of those keys' tables (KeyDoc: type, default, allowed values, meaning), in
  /// reading order: what `scatterlab info --keys` prints and docs/scene-format.md is checked
  /// against.
  std::vector<KeyDoc> keyDocs;
  /// Whether the method has a variant of every stage on `backend`.
  std::function<bool(Backend backend)> runsOn;
  /// Reads the method's keys from the render object (whichever backend runs) and returns the
  /// method for `backend`, which runsOn. Must not call finish(); throws ConfigError.
  std::function<std::unique_ptr<Method>(Params& render, const Scene& scene, Backend backend,
                                        const std::string& backendNote)>
      create;
};

Registry<MethodEntry>& methods();

/// The method of a scene whose render object names none: the paper's (gradient-based
/// interpolation with dynamic sampling), on the CPU and the GPU. `exact` is the reference, at
/// many times its cost (docs/RESULTS.md).
inline constexpr std::string_view kDefaultMethod = "adaptive";

/// Creates the method the scene's render object names (default kDefaultMethod), or `methodOverride`
/// when non-empty — exactly as if render.method were set to it. backend: "cpu", "gpu" or
/// "auto" (a hardware GPU when one is there and the method runs on it, else the CPU); the
/// render object's `backend` applies when this is "auto". Any other backend string ("GPU",
/// "cuda", "") is a ConfigError listing the three. Keys that only other registered
/// methods read are tolerated and listed in Method::ignoredKeys (so a reference can be rendered
/// from any scene); any other unknown key is a ConfigError naming it, and so is a backend the
/// method has no variant on.
std::unique_ptr<Method> createMethod(const Scene& scene, const std::string& methodOverride = "",
                                     const std::string& backend = "auto");

}  // namespace scatterlab
