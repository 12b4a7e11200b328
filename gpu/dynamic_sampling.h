#pragma once
/// Dynamic sampling on the GPU (paper Sec. 5): the GPU twin of scatterlab::dynamicSampling
/// (sampling/dynamic_sampling.h), with the same semantics sample for sample. Resident (issue
/// 33): the host uploads the initial samples and enqueues every pass; nothing waits for the GPU
/// until someone reads the result. Per level: evaluate (one compute dispatch, indirect after
/// level 0: S, ∇S, the probes' S and density, τ to the viewer, E_j (Eq. 5)); on level 0 a
/// one-invocation pass turns the contributions into the threshold (the mean in double, as
/// relativeErrorScale); with a sample budget the level's worst-first cut (budgetedSplit's error
/// groups: a keys pass raising each vertex of G_{k+1} to its worst candidate's group, the
/// vertices' histogram, and a one-workgroup cut, dynamic_budget.comp.glsl); split (a dispatch
/// that marks the vertices of G_{k+1} inside the spheres of the samples that split, compared in
/// double: inSet, ancestor by atomicMin) and compact (a Blelloch scan, gpu/scan.h, a
/// one-invocation pass writing |Q^{k+1}| and the next level's dispatch size into a buffer, and a
/// scatter into the next level's sample list, in ascending vertex order). After the last level,
/// with a budget, the top-up's cut from the same histograms; then the final list is assembled
/// in the CPU's order (each level's kept samples, then the top-up's children, whose S is traced
/// in place: dynamic_assemble.comp.glsl). Each level's list has a capacity fixed up front
/// (min(vertices of its grid, kMaxLevelSamples)); a level that asks for more is cut on the GPU
/// and reported (GpuError) when the pass is read. The buffers live in a
/// DynamicSamplingWorkspace, kept across frames by the GPU refiner. Everything here needs a GL
/// context (gpu::context(), created on demand).

#include <cstdint>
#include <span>
#include <vector>

#include "gpu/device_samples.h"
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
/// S/∇S and E, and per split level its vertices' error keys; the grid information buffer and scan
/// scratch of the largest grid; the counts; the budget's histograms; the final list. Grown when a
/// pass needs more, never shrunk; reused by every later pass and frame (one per GPU refiner,
/// gpu/register.cpp). Holds GL objects: destroy it while the context exists.
struct DynamicSamplingWorkspace {
  struct Level {
    std::size_t capacity = 0;
    Buffer samples;     ///< GpuSamplePoint per sample: position, valid radius
    Buffer ancestors;   ///< int32 per sample: index of its level-0 ancestor
    Buffer radiance;    ///< GpuRadianceRecord per sample
    Buffer errors;      ///< float E_j per sample (level 0: then the contributions)
    Buffer vertexKeys;  ///< budget: uint per vertex of G_{k+1}: 1 + its worst candidate's group
  };
  std::vector<Level> levels;
  /// uint: counts per level, overflow records, indirect dispatch sizes, the budget's cuts and
  /// counts, the final list's parts (layout: CountSlots in dynamic_sampling.cpp).
  Buffer counts;
  Buffer threshold;   ///< double error scale, double threshold
  Buffer rootTau;     ///< float τ per level-0 sample
  Buffer probeSums;   ///< float per sample and group of kProbeGroup probes (the probe pass)
  Buffer histograms;  ///< budget: per split level, uint candidates then vertices per error group
  /// Grid information buffer of G_{k+1} and its scan; inSet / offsets also the flags of every
  /// part of the final list and their scan.
  Buffer inSet, vertexAncestors, offsets;
  ScanScratch scanSums;               ///< block sums per recursion depth of the scan
  std::size_t vertices = 0;           ///< capacity of inSet / vertexAncestors / offsets
  Buffer finalPoints, finalRadiance;  ///< the final list when no DeviceSamples takes it
  Buffer parts;  ///< uvec4 per part of the final list (dynamic_assemble.comp.glsl's SL_PART_ENDS)
  /// Most samples a level above 0 may hold (tests lower it to reach the overflow report).
  std::size_t maxLevelSamples = kMaxLevelSamples;
  /// What the last pass enqueued, for reading it (readDynamicSamplingGpu).
  struct Pass {
    DynamicSamplingSettings settings;
    std::size_t initial = 0;
    long long budget = 0;
    std::size_t finalCapacity = 0;
    std::vector<double> enqueueMs;
    const Buffer* finalPoints = nullptr;  ///< where the final list is
    const Buffer* finalRadiance = nullptr;
  } pass;
};

/// Runs recursive splitting from `initial` (positions and radii) entirely with GL compute
/// passes, the budget's splits and top-up included, and reads the result back once at the end
/// (readDynamicSamplingGpu). Same result as dynamicSampling() with the CPU volume tracer up to
/// floating-point differences of S (1e-3); the split decisions agree unless some E_j is within
/// rounding of the threshold or of an error group's edge. `errors`, when given, receives E of
/// every evaluated sample per split level (in evaluation order). GPU times per pass go to
/// `timer` (stages "ds evaluate+error", "ds threshold", "ds budget", "ds split", "ds scan",
/// "ds compact", "ds assemble", "ds read-back"); LevelStats::ms is the host time to enqueue a
/// level (the levels do not wait for each other). `shadows`: the scene objects' shadow maps
/// (null without objects), so that S at samples and probes carries V_l as on the CPU.
/// `workspace`: buffers kept from an earlier call (null: made for this call). `resident`: the
/// final list is left in it (DeviceSamples::onDevice: its count on the GPU only) and nothing is
/// read: the result holds no samples and no levels (read them after the frame with
/// readDynamicSamplingGpu(*workspace, false)); needs `workspace`.
DynamicSamplingResult dynamicSamplingGpu(
    const Scene& scene, const Volume& density, std::vector<RadianceSample> initial,
    TracerSteps steps, const DynamicSamplingSettings& settings, StageTimer* timer = nullptr,
    std::vector<std::vector<float>>* errors = nullptr, const ShadowMaps* shadows = nullptr,
    DynamicSamplingWorkspace* workspace = nullptr, DeviceSamples* resident = nullptr);

/// Reads the last pass of `w` (a host wait): the level statistics, and with `samples` the
/// final samples (positions, radii, levels, S and ∇S) in the CPU's order; `errors` as
/// dynamicSamplingGpu's. Throws GpuError when a level or the final list asked for more than its
/// capacity.
DynamicSamplingResult readDynamicSamplingGpu(const DynamicSamplingWorkspace& w, bool samples,
                                             std::vector<std::vector<float>>* errors = nullptr);

}  // namespace scatterlab::gpu
