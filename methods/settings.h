#pragma once
/// The settings of the volume pipelines, read from a scene's render object in one place, the
/// same whichever backend runs (methods/settings.cpp holds the key table). Which keys a method
/// reads follows from its stages (MethodDesc).

#include <memory>
#include <string>
#include <vector>

#include "core/params.h"
#include "core/scene.h"
#include "core/stages.h"

namespace scatterlab {

/// One method: which stages it runs (by registered name), each with a variant per backend.
/// Registered once in methods/register.cpp; a PipelineMethod runs it.
struct MethodDesc {
  std::string name;
  std::string summary;               ///< one line
  bool sampler = false;              ///< a sampler and the radiance evaluator run (samples)
  std::string refiner;               ///< a SampleRefiner between them ("dynamic"), or empty
  std::string reconstruction;        ///< reconstructions() entry, or empty (no radiance volume)
  std::string integrator;            ///< default integrators() entry (render.integrator)
  bool integratorSelectable = true;  ///< whether render.integrator may replace it
  /// The fidelity extensions (docs/fidelity.md) are on by default (`gradient`, `adaptive`); the
  /// baselines keep the paper's algorithm unless asked. render.paper turns them all off.
  bool extended = false;
  /// The render.sampler a user who sets none gets when the extensions are on (empty: the
  /// paper's default, which also applies with render.paper).
  std::string extendedSampler;
  /// Whether the method reads march_step and min_transmittance (false: light-space-march, whose
  /// view rays take `steps` steps each).
  bool viewMarch = true;

  /// Whether the method builds a source-radiance volume (and reads its keys).
  bool radianceVolume() const { return !reconstruction.empty(); }
};

/// Key table of the pipeline settings (render keys; sampler.* and the refiner's keys have
/// their own tables in sampling/).
const std::vector<KeyDoc>& pipelineKeys();
/// Key table of render.shadow_map (ShadowMapSettings).
const std::vector<KeyDoc>& shadowMapKeys();

/// Key tables of the real-time methods (shading/post_process.h), read for the methods whose
/// integrator is "light-space-march" or "radial-blur" (docs/light-space-march.md,
/// docs/radial-blur.md).
const std::vector<KeyDoc>& lightSpaceMarchKeys();
const std::vector<KeyDoc>& radialBlurKeys();

/// Reads the keys `desc`'s stages use from the render object: march_step, min_transmittance,
/// delta1 always; delta2 with samples; radiance_resolution and slicing with a radiance volume.
/// Must not call finish().
PipelineSettings parsePipelineSettings(Params& render, const Scene& scene, const MethodDesc& desc);

/// The top-level render keys a method with `desc` reads (for createMethod's tolerance of other
/// methods' keys): the pipeline keys above, "sampler", "evaluator", "integrator" and the
/// refiner's keys, as its stages need them.
std::vector<std::string> methodKeys(const MethodDesc& desc);

/// The render.sampler object; `type` receives the sampler's name. Default: `extendedDefault`
/// (JSON of a sampler object) when non-empty, else the paper's: Gaussian centres when the
/// medium has Gaussians, else 512 jittered samples.
/// `plannedSamples`, when given, receives about how many samples the sampler will make (its
/// `count`, or the medium's Gaussians for gaussian-centres) for checkRenderPlan.
std::unique_ptr<Sampler> makeSampler(Params& render, const Scene& scene, std::string& type,
                                     const std::string& extendedDefault = "",
                                     long long* plannedSamples = nullptr);

struct DynamicSamplingSettings;

/// Checks a render's plan before anything is built (docs/reliability.md):
///  - memory: the sum of its planned allocations (MemoryPlan: the density volume, the
///    max-density grid, the radiance volume and the fused density + radiance volume of the fast
///    march, the image, the sample set, dynamic sampling's level-0 probes and finest grid
///    buffer, a .sog medium's Gaussians and hash) against the memory limit, a LimitError naming
///    the largest contributors;
///  - work: the light-march steps of evaluating the samples, samples × traced points (S, the 6
///    central differences of ∇S when `gradients`, the probes of dynamic sampling's level 0)
///    × ⌈diagonal / delta1⌉ × lights, against kMaxLightSteps, a LimitError naming the keys.
/// `samples`: the planned count (makeSampler), 0 without a sampler; `dynamic`: null without
/// dynamic sampling; `cpuRayMarcher`: the image is marched by the CPU's ray-marcher (which fuses
/// density and radiance into one volume when fast_march is on and their grids agree); `cpu`: the
/// method runs on the CPU, whose froxel volume, transmittance maps and shadow maps are host
/// arrays in the plan (`render.froxel_grid`, `render.transmittance_map_resolution`,
/// `render.shadow_map.resolution`).
void checkRenderPlan(Params& render, const Scene& scene, const MethodDesc& desc,
                     const PipelineSettings& settings, long long samples, bool gradients,
                     const DynamicSamplingSettings* dynamic, bool cpuRayMarcher, bool cpu = true);

}  // namespace scatterlab
