#pragma once
/// The GPU radiance evaluator "volume-tracer" (DESIGN.md §3), registered in gpu/register.cpp.
/// The interface override works in a GpuFrame (gpu/frame.h); the Volume overload is the pass.

#include <optional>
#include <span>

#include "core/stages.h"
#include "gpu/gl.h"
#include "gpu/shaders.h"
#include "gpu/shadow_maps.h"
#include "gpu/timer.h"
#include "gpu/tracing.h"
#include "gpu/volume.h"

namespace scatterlab::gpu {

/// S and ∇S at every sample in one compute dispatch (GPU twin of the CPU volume tracer),
/// parallel over (sample, point, light) (TracerShape):
/// S(x) = SourceRadiance(x, towards the camera position), ∇S by central differences with step
/// delta2 along each world axis, each offset point with its own view direction.
class VolumeTracerGpu : public RadianceEvaluator {
 public:
  /// steps: tracing and central-difference steps (world units), and whether V = S / A (or
  /// ln V) is evaluated instead of S, as the CPU evaluator does (PipelineSettings).
  /// shadowMap: how scene objects' visibility is looked up (render.shadow_map).
  explicit VolumeTracerGpu(TracerSteps steps, ShadowMapSettings shadowMap = {})
      : delta1_(steps.delta1),
        delta2_(steps.delta2),
        factor_(steps.factorLights),
        log_(steps.logValues()),
        lamp_(steps.lampModel),
        reach_(steps.reach),
        shadowMap_(shadowMap) {}
  void evaluate(Frame& frame, const Scene& scene, std::span<RadianceSample> samples,
                bool gradients) override;
  /// `shadows`: the objects' shadow maps (null without objects). Uploads the positions, traces
  /// and reads S and ∇S back into `samples`.
  void evaluate(const Scene& scene, const Volume& density, std::span<RadianceSample> samples,
                bool gradients, StageTimer* timer, const ShadowMaps* shadows = nullptr);
  /// The pass: S and ∇S of the first `count` GpuSamplePoint of `points` into the
  /// GpuRadianceRecord of `results` (binding::kSamples, kRadiance), left on the GPU.
  void trace(const Scene& scene, const Volume& density, const Buffer& points, std::size_t count,
             const Buffer& results, bool gradients, StageTimer* timer, const ShadowMaps* shadows);

 private:
  float delta1_, delta2_;
  bool factor_, log_, lamp_;
  float reach_;
  ShadowMapSettings shadowMap_;
};

/// The tracer's pass name (its GPU time and its invocations in the stats).
inline constexpr const char* kTracerPass = "radiance evaluation";

/// What a tracer program computes: ∇S too, V = S / A (factored lights) with A's lamp model,
/// ln V (TracerSteps, DynamicSamplingSettings).
struct TracerVariant {
  bool gradients = true, factorLights = false, lampModel = false, logSpace = false;
  /// TracerSteps::reach with factorLights (SL_LIT_REACH; 0: every sample traced).
  float reach = 0.0f;
};

/// traceLevel's firstSlot when the samples start at 0.
inline constexpr std::size_t kFromZero = std::size_t(-1);

/// The tracer's pass over level `level` of dynamic sampling (gpu/dynamic_sampling.cpp): S and
/// ∇S of the first counts[level] points of `points` into `results` (from counts[firstSlot] on,
/// unless kFromZero), the counts read on the GPU from `counts` (binding::kLevelCounts: no
/// read-back), at most `capacity` samples; parallel over (sample, point, light) as the
/// evaluator's pass. `inputs` applied (TracingInputs), pass name "ds trace", timed by the
/// caller's scope. Workgroups: for the capacity (at most kMaxTraceGroups; they stride over the
/// count), or, with `indirectSlot`, the (x, 1, 1) that the GPU's count pass left at
/// counts[indirectSlot] for the level's own count (dynamic_level.comp.glsl).
void traceLevel(const TracingInputs& inputs, std::size_t lights, const TracerVariant& variant,
                float delta2, const Buffer& points, const Buffer& results, const Buffer& counts,
                std::size_t level, std::size_t capacity, std::size_t firstSlot = kFromZero,
                std::optional<std::size_t> indirectSlot = std::nullopt);

/// The most workgroups of a level's tracer and probe passes (up to 1.8 M invocations with
/// gradients, several waves of a large GPU); they stride over the rest.
inline constexpr unsigned kMaxTraceGroups = 4096;

/// How the tracer's workgroups are laid out (volume_tracer.comp.glsl): `lanes` invocations split
/// the lights of each of a sample's `rows` points (7 with gradients: x and x ± δ2·e_a), `slots`
/// samples per workgroup (lanes × slots = 32, one sample a workgroup from 32 lanes on).
struct TracerShape {
  int lanes = 1, rows = 1, slots = 32;
};
TracerShape tracerShape(std::size_t lights, bool gradients);

/// The tracer's shader and defines for `shape` and `variant`, the empty-space skip of shadow rays
/// included; the caller adds its own defines and addShadowVariant (dynamic sampling's probe pass:
/// SL_PROBES, volume_tracer.comp.glsl).
ProgramVariant tracerProgramVariant(const TracerShape& shape, const TracerVariant& variant);

/// Reads the GpuRadianceRecord of `results` back into S and ∇S of `samples` (a host wait).
void readRadianceRecords(const Buffer& results, std::span<RadianceSample> samples);

}  // namespace scatterlab::gpu
