#pragma once
/// Dynamic sampling on the GPU (paper Sec. 5): the GPU twin of scatterlab::dynamicSampling
/// (sampling/dynamic_sampling.h), with the same semantics sample for sample. Resident: the host
/// uploads the initial samples and reads the result back once, after the last level; in
/// between every level runs without waiting for the host. Per level: evaluate (one compute
/// dispatch, indirect after level 0: S, ∇S, the probes' S and density, τ to the viewer, E_j
/// (Eq. 5)); on level 0 a one-invocation pass turns the contributions into the threshold (the
/// mean in double, as relativeErrorScale); split (a dispatch that marks the vertices of G_{k+1}
/// inside the spheres of the samples whose E_j exceeds the threshold, compared in double:
/// inSet, ancestor by atomicMin) and compact (a Blelloch scan, gpu/shaders/scan.comp.glsl, a
/// one-invocation pass writing |Q^{k+1}| and the next level's dispatch size into a buffer, and
/// a scatter into the next level's sample list, in ascending vertex order). Each level's list
/// has a capacity fixed up front (min(vertices of its grid, kMaxLevelSamples)); a level that
/// asks for more is cut on the GPU and reported (GpuError) when the pass is read back. The
/// buffers live in a DynamicSamplingWorkspace, kept across frames by the GPU refiner. Everything
/// here needs a GL context (gpu::context(), created on demand).

#include <cstdint>
#include <span>
#include <vector>

#include "gpu/records.h"
#include "gpu/scan.h"
#include "gpu/timer.h"
#include "gpu/tracing.h"
#include "gpu/volume.h"
#include "sampling/dynamic_sampling.h"

namespace scatterlab::gpu {

/// Most samples one level above level 0 may hold (its list's capacity is the smaller of this and
/// its grid's vertex count): 2^21 samples, 176 MiB of buffers per level (88 bytes a sample).
inline constexpr std::size_t kMaxLevelSamples = std::size_t(1) << 21;

/// The GPU buffers of dynamicSamplingGpu: per level the sample list (positions, ancestors),
/// S/∇S and E; the grid information buffer and scan scratch of the largest grid; the counts.
/// Grown when a pass needs more, never shrunk; reused by every later pass and frame (one per
/// GPU refiner, gpu/register.cpp). Holds GL objects: destroy it while the context exists.
struct DynamicSamplingWorkspace {
  struct Level {
    std::size_t capacity = 0;
    Buffer samples;    ///< GpuSamplePoint per sample: position, valid radius
    Buffer ancestors;  ///< int32 per sample: index of its level-0 ancestor
    Buffer radiance;   ///< GpuRadianceRecord per sample
    Buffer errors;     ///< float E_j per sample (level 0: then the contributions)
  };
  std::vector<Level> levels;
  Buffer counts;     ///< uint: counts per level, overflow record, indirect dispatch sizes
  Buffer threshold;  ///< double error scale, double threshold
  Buffer rootTau;    ///< float τ per level-0 sample
  Buffer probeSums;  ///< float per sample and group of kProbeGroup probes (the probe pass)
  Buffer inSet, vertexAncestors, offsets;  ///< grid information buffer of G_{k+1}, its scan
  ScanScratch scanSums;                    ///< block sums per recursion depth of the scan
  std::size_t vertices = 0;                ///< capacity of inSet / vertexAncestors / offsets
  /// Most samples a level above 0 may hold (tests lower it to reach the overflow report).
  std::size_t maxLevelSamples = kMaxLevelSamples;
};

/// Runs recursive splitting from `initial` (positions and radii) entirely with GL compute
/// passes, reading back once at the end of the pass; with a sample budget (sampleBudget() > 0)
/// each split level's E is read back and its splits are decided on the host by the CPU's
/// budgetedSplit(), which uploads the next level (one pass, one read-back per level). Same result
/// as dynamicSampling() with the CPU volume tracer up to floating-point differences of S (1e-3);
/// the split decisions agree unless some E_j is within rounding of the threshold (compared in
/// double, as on the CPU). `errors`, when given, receives E of every evaluated sample per split
/// level (in evaluation order) of the pass returned. GPU times per pass go to `timer` (stages
/// "ds evaluate+error", "ds threshold", "ds split", "ds scan", "ds compact", "ds read-back");
/// LevelStats::ms is the host time to enqueue a level (the levels no longer wait for each
/// other). `shadows`: the scene objects' shadow maps (null without objects), so that S at
/// samples and probes carries V_l as on the CPU. `workspace`: buffers kept from an earlier call
/// (null: made for this call).
DynamicSamplingResult dynamicSamplingGpu(const Scene& scene, const Volume& density,
                                         std::vector<RadianceSample> initial, TracerSteps steps,
                                         const DynamicSamplingSettings& settings,
                                         StageTimer* timer = nullptr,
                                         std::vector<std::vector<float>>* errors = nullptr,
                                         const ShadowMaps* shadows = nullptr,
                                         DynamicSamplingWorkspace* workspace = nullptr);

}  // namespace scatterlab::gpu
