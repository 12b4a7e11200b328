#pragma once
/// The settings of the volume pipelines, read from a scene's render object before a backend is
/// chosen, so the same whichever backend runs. Which keys a method reads follows from its
/// stages: the pipeline's own keys are here (settings.cpp), each stage's in its family's own
/// file (StageDecl).

#include <memory>
#include <string>
#include <vector>

#include "core/params.h"
#include "core/scene.h"
#include "core/stages.h"

namespace scatterlab {

/// The sampler a method uses when render.sampler is not given and the extensions are on.
struct SamplerChoice {
  std::string type = {};  ///< empty: the paper's default (see makeSampler)
  long long count = 0;
  bool atMost = false;  ///< count is a ceiling (the cell samplers' at_most)
};

/// One method: which stages it runs (by registered name), each with a variant per backend.
/// Registered once in methods/register.cpp, one row with designated initializers; a
/// PipelineMethod runs it. What each stage reads and does is its own declaration (StageDecl).
struct MethodDesc {
  std::string name;
  std::string summary;   ///< one line
  bool sampler = false;  ///< a sampler and the radiance evaluator run (samples)
  /// radianceEvaluators() entry run with a sampler (render.evaluator may replace it).
  std::string evaluator = "volume-tracer";
  std::string refiner = {};         ///< a SampleRefiner between them ("dynamic"), or empty
  std::string reconstruction = {};  ///< reconstructions() entry, or empty (no radiance volume)
  /// The reconstructions() entry the whole scene falls back to where tracing it costs less
  /// than the sampled path (voxelsInstead(), key voxel_switch), or empty.
  std::string wholeSceneFallback = {};
  std::string integrator = {};       ///< default integrators() entry (render.integrator)
  bool integratorSelectable = true;  ///< whether render.integrator may replace it
  /// The fidelity extensions (docs/fidelity.md) are on by default (`gradient`, `adaptive`); the
  /// baselines keep the paper's algorithm unless asked. render.paper turns them all off.
  bool extended = false;
  /// The render.sampler a user who sets none gets when the extensions are on (measured best
  /// at <= 4000 samples on the fidelity scenes: docs/fidelity.md); with render.paper, or an
  /// empty type, the paper's default.
  SamplerChoice extendedSampler = {};

  /// Whether the method builds a source-radiance volume (and reads its keys).
  bool radianceVolume() const { return !reconstruction.empty(); }
};

/// A method resolved once for one render object and one backend: the stages that run (their
/// declarations and chosen names), their settings, its sampler and planned sample count, and
/// what the scene set that this backend does not read. The pipeline, the render plan's checks
/// and the stats read it; nothing after planMethod() looks a stage up by name again.
struct MethodPlan {
  MethodDesc desc;
  Backend backend = Backend::Cpu;
  PipelineSettings settings;
  /// The evaluator and integrator that run (render.evaluator, render.integrator, else the
  /// row's); the evaluator empty without samples.
  std::string evaluator, integrator;
  /// The declarations of the stages that run, in reading order: evaluator, reconstruction,
  /// refiner, integrator.
  std::vector<const StageDecl*> stages;
  const StageDecl* integratorDecl = nullptr;  ///< the last of `stages`
  /// With samples: the sampler (its keys read), its name and its planned count.
  std::unique_ptr<Sampler> sampler;
  std::string samplerType;
  long long plannedSamples = 0;
  /// The keys the scene set that mean nothing on `backend` (KeyDoc::only; slicing also under
  /// the compute pipeline), as key paths: the stats' unused_keys.
  std::vector<std::string> unusedKeys;
};

/// Resolves `desc` for `backend`: reads render.evaluator and render.integrator (unknown names
/// are ConfigErrors with suggestions), then every key of the stages that run (the same on
/// every backend, so a scene valid on one is valid on the other), the sampler's, and checks
/// the view march's and the light-tracing stages' work. Whether each stage has a variant on
/// `backend` is checked when the variants are built (makePipelineMethod).
MethodPlan planMethod(const MethodDesc& desc, Params& render, const Scene& scene, Backend backend);

/// Every render key `desc` reads, as rows of the tables that own them, in reading order: the
/// pipeline's own (delta1, shadow_map; with samples paper, factor_lights, log_space, sampler,
/// evaluator; with a radiance volume radiance_resolution, gpu_pipeline, integrator), the view
/// march's when its integrator declares one, then each of its stages' own (StageDecl::keys).
/// What methodKeys(), docs and tests derive from.
std::vector<KeyDoc> methodKeyTable(const MethodDesc& desc);

/// The top-level render keys a method with `desc` reads (the names of methodKeyTable()): for
/// createMethod's tolerance of other methods' keys.
std::vector<std::string> methodKeys(const MethodDesc& desc);

/// Default of the whole-scene fallback (key `voxel_switch`, PipelineSettings::voxelSwitch):
/// chosen on the population of scenes, for adaptive (docs/fidelity.md, "The whole-scene
/// fallback") and for gradient ("gradient's whole-scene fallback").
inline constexpr double kVoxelSwitch = 4.0;

/// The points a sample whose gradient is evaluated traces: S and the six central differences of
/// ∇S (the work check of checkRenderPlan, the whole-scene fallback's count of gradient's traces).
inline constexpr double kGradientSampleTraces = 7.0;

/// The whole-scene fallback's rule, one for every method and backend: whether per-voxel, tracing
/// S at `litVoxels` (the occupied voxels a light reaches), costs at most `voxelSwitch` × the
/// `sampledTraces` of the method's own sampled path (gradient: its samples × 7, S and the six
/// differences of ∇S; adaptive: its initial samples × (1 + probes)). 0 turns it off; no traces,
/// nothing to compare.
bool voxelsInstead(double voxelSwitch, long long litVoxels, double sampledTraces);

/// Key table of render.shadow_map (ShadowMapSettings).
const std::vector<KeyDoc>& shadowMapKeys();

/// Reads the keys of methodKeyTable(desc) into the settings the stage variants are built from,
/// except sampler, evaluator and integrator (planMethod reads them), and checks the work of the
/// view march and of the stages that trace light at every step or voxel; for the row's default
/// stages (planMethod: the chosen ones). Must not call finish().
PipelineSettings parsePipelineSettings(Params& render, const Scene& scene, const MethodDesc& desc);

/// The render.sampler object; `type` receives the sampler's name. Default: `extendedDefault`
/// when its type is set, else the paper's: Gaussian centres when the medium has Gaussians,
/// else jittered samples (with the sampler's default count).
std::unique_ptr<Sampler> makeSampler(Params& render, const Scene& scene, std::string& type,
                                     const SamplerChoice& extendedDefault = {});

/// Checks a render's plan before anything is built (docs/reliability.md):
///  - memory: the sum of its planned allocations (MemoryPlan: the density volume, the
///    max-density grid, the radiance volume and the fused density + radiance volume of the fast
///    march, the image, the sample set, dynamic sampling's level-0 probes and finest grid
///    buffer, a .sog medium's Gaussians and hash) against the memory limit, a LimitError naming
///    the largest contributors;
///  - work: the light-march steps of evaluating the samples, samples × traced points (S, the 6
///    central differences of ∇S when `gradients` or a stage traces them, the probes of a
///    refiner's first level: StageWork) × ⌈diagonal / delta1⌉ × lights, against
///    kMaxLightSteps, a LimitError naming the keys.
/// The samples are plan.plannedSamples (0 without a sampler); the fused volume of a CPU
/// integrator that fuses density and radiance when fast_march is on and their grids agree
/// (StageDecl::fusedVolumeOnCpu) and the competitors' host arrays (StageDecl::work: froxel
/// volume, transmittance maps, shadow maps) count where plan.backend is the CPU.
void checkRenderPlan(Params& render, const Scene& scene, const MethodPlan& plan, bool gradients);

}  // namespace scatterlab
