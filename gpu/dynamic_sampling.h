#pragma once
/// Dynamic sampling on the GPU (paper Sec. 5): the GPU twin of scatterlab::dynamicSampling
/// (sampling/dynamic_sampling.h), with the same semantics sample for sample. Per level, three
/// steps: evaluate (one compute dispatch: S, ∇S, the probes' S and density, τ to the viewer,
/// E_j (Eq. 5) and the split flag), split (error statistics, and a dispatch that marks the
/// vertices of G_{k+1} inside the split spheres in the grid information buffer: inSet, ancestor
/// by atomicMin) and compact (a work-efficient Blelloch scan, gpu/shaders/scan.comp.glsl, and a
/// scatter into the next level's sample list, in ascending vertex order, which stays on the
/// GPU). Each level's samples, S/∇S, errors and flags are read back to assemble the result
/// (kept samples in the CPU's order) and the stats. Everything here needs a GL context
/// (gpu::context(), created on demand).

#include <cstdint>
#include <span>
#include <vector>

#include "gpu/records.h"
#include "gpu/stages.h"
#include "gpu/timer.h"
#include "gpu/volume.h"
#include "sampling/dynamic_sampling.h"

namespace scatterlab::gpu {

/// Steps of the GPU volume tracer used by dynamic sampling (render keys delta1, delta2).
struct DynamicSamplingGpuSteps {
  float delta1 = 0.0f;        ///< tracing step towards the lights
  float delta2 = 0.0f;        ///< central-difference step of ∇S
  bool factorLights = false;  ///< samples hold V = S / A (PipelineSettings::factorLights)
  bool logSpace = false;      ///< ... or ln V (with factorLights)
};

/// Runs recursive splitting from `initial` (positions and radii) entirely with GL compute
/// passes: per level evaluateLevelGpu, setSplitFlags (on the host: the threshold of a relative
/// ε needs level 0's contributions), then (but on the finest level) splitLevelGpu and
/// compactLevelGpu; with settings.maxSamples, the passes are repeated by withSampleBudget()
/// exactly as on the CPU. Same result as dynamicSampling() with the CPU volume tracer up to
/// floating-point differences of S (1e-3); the split decisions agree unless some E_j is within
/// rounding of the threshold (compared in double, as on the CPU). `errors`, when given,
/// receives E of every evaluated sample per split level (in evaluation order) of the pass
/// returned. GPU times per pass go to `timer` (stages "ds evaluate+error", "ds split", "ds
/// scan", "ds compact"). `shadows`: the scene objects' shadow maps (null without objects), so
/// that S at samples and probes carries V_l as on the CPU.
DynamicSamplingResult dynamicSamplingGpu(const Scene& scene, const Volume& density,
                                         std::vector<RadianceSample> initial,
                                         DynamicSamplingGpuSteps steps,
                                         const DynamicSamplingSettings& settings,
                                         StageTimer* timer = nullptr,
                                         std::vector<std::vector<float>>* errors = nullptr,
                                         const ShadowMaps* shadows = nullptr);

/// The sample list Q^k of one level, on the GPU.
struct DynamicLevelGpu {
  std::size_t level = 0;  ///< k (0: the initial set)
  std::size_t count = 0;  ///< |Q^k|
  Buffer samples;         ///< GpuSamplePoint per sample: position, valid radius
  Buffer ancestors;       ///< int32 per sample: index of its level-0 ancestor
};

/// What the evaluation of a level computed: read back for the result, and the split flags
/// also kept on the GPU for splitLevelGpu.
struct LevelEvaluationGpu {
  std::vector<GpuSamplePoint> samples;      ///< the level's positions and radii
  std::vector<GpuRadianceRecord> radiance;  ///< S and ∇S per sample
  std::vector<float> errors;                ///< E_j (0 on the final level)
  std::vector<float> contributions;  ///< level 0, not final: R³·mean|S|·D·τ (sampleContribution)
  std::vector<std::uint32_t> splitFlags;  ///< 1 where E_j > threshold (set by setSplitFlags)
  Buffer flags;                           ///< splitFlags on the GPU
};

/// The grid information buffer of G_{k+1} on the GPU, as splitting leaves it.
struct GridInfoGpu {
  GridInfoBuffer grid;     ///< the grid's geometry (its host arrays are not used)
  Buffer inSet;            ///< uint per vertex: 1 when the vertex is in Q^{k+1}
  Buffer vertexAncestors;  ///< int32 per vertex: least ancestor marking it, INT_MAX = none
};

/// Evaluate: one dispatch computes, for every sample of `level`, S and ∇S (central
/// differences, step steps.delta2; V or ln V instead of S as steps says) and, unless `final`, the
/// probes' S and density, τ to the viewer (traced on level 0 and stored in `rootTau`, one float per
/// level-0 sample; later levels read their ancestor's unless settings.perSampleTau), E_j and, on
/// level 0, the contributions. The split flags are left to setSplitFlags. `inputs` must be those of
/// `density`. GPU time: "ds evaluate+error".
LevelEvaluationGpu evaluateLevelGpu(const TracingInputs& inputs, const Volume& density,
                                    const DynamicLevelGpu& level, const Buffer& rootTau, bool final,
                                    const DynamicSamplingGpuSteps& steps,
                                    const DynamicSamplingSettings& settings,
                                    StageTimer* timer = nullptr);

/// The split flags E_j > threshold of an evaluated level (host, in double: the CPU's
/// comparison), uploaded to eval.flags for splitLevelGpu.
void setSplitFlags(LevelEvaluationGpu& eval, double threshold);

/// Split: adds the level's split count, largest and 90th-percentile E_j to `stats`, and marks,
/// in a new grid information buffer of G_{k+1} (`resolution`³ vertices over `bounds`), every
/// vertex strictly inside the valid sphere of a split sample, with the least ancestor of the
/// spheres that cover it (GridInfoBuffer::markSphere). GPU time: "ds split".
GridInfoGpu splitLevelGpu(const DynamicLevelGpu& level, const LevelEvaluationGpu& eval,
                          const Box& bounds, int resolution, LevelStats& stats,
                          StageTimer* timer = nullptr);

/// Compact: an exclusive scan of the marked vertices and a scatter of them, in ascending
/// vertex order, into the sample list of level `level` (positions at the vertices, radius
/// GridInfoBuffer::radius(), the vertices' ancestors). GPU times: "ds scan", "ds compact".
DynamicLevelGpu compactLevelGpu(const GridInfoGpu& grid, std::size_t level,
                                StageTimer* timer = nullptr);

/// Exclusive scan of 0/1 flags by compute shader (the scan used by dynamicSamplingGpu, on host
/// data: upload, scan, read back), for comparison with scatterlab::exclusiveScan. Returns the
/// total.
std::uint32_t exclusiveScanGpu(std::span<const std::uint8_t> flags,
                               std::span<std::uint32_t> offsets);

}  // namespace scatterlab::gpu
