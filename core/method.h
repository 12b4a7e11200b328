#pragma once
/// Stage interface: a whole rendering method (scene -> image), composed from the other stages
/// or standing alone (the exact reference). Implementations live in render/ (CPU) and gpu/.

#include <functional>
#include <memory>
#include <string>

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
  /// empty for methods without samples. For pictures of the sampling and for tests.
  std::vector<RadianceSample> samples;
  /// The volumes the method built, for export (`render --density-vdb / --radiance-vdb`) and
  /// tests: the density volume (CPU methods), the source-radiance volume S (CPU methods that
  /// build one; `exact` has none). Null where a method has none or keeps it on the GPU.
  std::shared_ptr<const DensityGrid> density;
  std::shared_ptr<const RadianceGrid> radiance;
};

class Method {
 public:
  virtual ~Method() = default;
  /// Renders `scene` (whose `render` settings this method was created from). `progress` may be
  /// null. Throws scatterlab::Error on failure. CPU methods need no GL context.
  virtual RenderResult render(const Scene& scene, Progress* progress) = 0;
};

/// Reads the method's own keys from the scene's render object ("method" and "backend" are
/// read by the caller) and validates them against `scene`. Must not call finish().
using MethodFactory = std::function<std::unique_ptr<Method>(Params& render, const Scene& scene,
                                                            const std::string& backend)>;

Registry<MethodFactory>& methods();

/// Creates the method the scene's render object names (default "exact"), or `methodOverride`
/// when non-empty. backend: "cpu", "gpu" or "auto". Keys of the render object that belong to
/// the scene's own method are tolerated when `methodOverride` replaces it (so that a reference
/// can be rendered from any scene); any other unknown key is a ConfigError.
std::unique_ptr<Method> createMethod(const Scene& scene, const std::string& methodOverride = "",
                                     const std::string& backend = "auto");

}  // namespace scatterlab
