#pragma once
/// Stage interfaces of the sample-based pipelines (DESIGN.md §3): sampler -> radiance
/// evaluator -> reconstruction -> integrator. Each is a small abstract class with one virtual
/// call per pass; variants are registered by name (CPU ones in sampling/ and render/, GPU ones
/// in gpu/). GPU variants hand their results back to host memory through the same signatures,
/// so one test body serves both.

#include <functional>
#include <memory>
#include <span>
#include <string>
#include <vector>

#include "core/grid.h"
#include "core/image.h"
#include "core/params.h"
#include "core/registry.h"
#include "core/scene.h"
#include "core/stats.h"

namespace scatterlab {

/// A radiance sample (paper Sec. 4): point, valid radius, source radiance S and its gradient.
struct RadianceSample {
  Vec3 position{0.0f};  ///< x_j, world space
  float radius = 0.0f;  ///< valid radius R_j, world units
  Vec3 S{0.0f};         ///< S(x_j, ω) per RGB channel (DESIGN.md §2; excludes σs and D)
  /// ∇S: dS[a] is the RGB derivative along world axis a (x, y, z), by central differences.
  Vec3 dS[3] = {Vec3(0.0f), Vec3(0.0f), Vec3(0.0f)};
  int level = 0;  ///< dynamic-sampling level (0 = initial set)
  /// Kernel weight for RBF reconstruction: w_j of the Gaussian a gaussian-centres sample came
  /// from (Zhou et al. 2007 weight their RBFs by it), 1 for other samplers.
  float weight = 1.0f;

  /// First-order Taylor estimate of S at p (paper Eq. 4's bracket).
  Vec3 taylor(const Vec3& p) const {
    const Vec3 d = p - position;
    return S + d.x * dS[0] + d.y * dS[1] + d.z * dS[2];
  }
};

/// Chooses sample points and valid radii (S and dS left zero).
class Sampler {
 public:
  virtual ~Sampler() = default;
  /// Generates samples for the scene; `density` is its density volume. Deterministic for a
  /// given scene and parameters.
  virtual std::vector<RadianceSample> generate(const Scene& scene, const DensityGrid& density) = 0;
};

/// Computes S (and ∇S when `gradients`) at each sample's position, by volume tracing with step
/// delta1 and central differences with step delta2 (paper Sec. 4). The view direction at x is
/// towards scene.camera.position.
class RadianceEvaluator {
 public:
  virtual ~RadianceEvaluator() = default;
  virtual void evaluate(const Scene& scene, const DensityGrid& density,
                        std::span<RadianceSample> samples, bool gradients) = 0;
};

/// What a reconstruction did.
struct ReconstructionStats {
  long long uncovered = 0;  ///< voxels with density but no covering sample
};

/// Builds the source-radiance volume `out` (bounds and dims preset by the caller) from samples.
class Reconstruction {
 public:
  virtual ~Reconstruction() = default;
  virtual ReconstructionStats reconstruct(const Scene& scene, const DensityGrid& density,
                                          std::span<const RadianceSample> samples,
                                          RadianceGrid& out) = 0;
};

/// Marches camera rays through density and source-radiance volumes into an image.
class Integrator {
 public:
  virtual ~Integrator() = default;
  virtual Image integrate(const Scene& scene, const DensityGrid& density,
                          const RadianceGrid& radiance) = 0;
};

template <class Stage>
using StageFactory = std::function<std::unique_ptr<Stage>(Params& params, const Scene& scene)>;

Registry<StageFactory<Sampler>>& samplers();
Registry<StageFactory<RadianceEvaluator>>& radianceEvaluators();
Registry<StageFactory<Reconstruction>>& reconstructions();
Registry<StageFactory<Integrator>>& integrators();

}  // namespace scatterlab
