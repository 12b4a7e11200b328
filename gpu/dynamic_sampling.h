#pragma once
/// Dynamic sampling on the GPU (paper Sec. 5): the GPU twin of scatterlab::dynamicSampling
/// (sampling/dynamic_sampling.h), with the same semantics sample for sample: per level, one
/// compute dispatch evaluates S, ∇S, the probes' S and density, τ to the viewer, E_j (Eq. 5)
/// and the split flag; a second marks the vertices of G_{k+1} inside the split spheres in the
/// grid information buffer (SSBOs: inSet, ancestor by atomicMin); a work-efficient Blelloch scan
/// (gpu/shaders/scan.comp.glsl) and a scatter compact them, in ascending vertex order, into the
/// next level's sample list, which stays on the GPU. Each level's samples, S/∇S, errors and
/// flags are read back to assemble the result (kept samples in the CPU's order) and the stats.
/// Everything here needs a GL context (gpu::context(), created on demand).

#include <cstdint>
#include <span>
#include <vector>

#include "gpu/timer.h"
#include "gpu/volume.h"
#include "sampling/dynamic_sampling.h"

namespace scatterlab::gpu {

/// Steps of the GPU volume tracer used by dynamic sampling (render keys delta1, delta2).
struct DynamicSamplingGpuSteps {
  float delta1 = 0.0f;  ///< tracing step towards the lights
  float delta2 = 0.0f;  ///< central-difference step of ∇S
};

/// Runs recursive splitting from `initial` (positions and radii) entirely with GL compute
/// passes. Same result as dynamicSampling() with the CPU volume tracer up to floating-point
/// differences of S (1e-3); the split decisions agree unless some E_j is within rounding of ε.
/// The comparison E > ε is done in float (ε rounded to float). `errors`, when given, receives
/// E of every evaluated sample per split level (in evaluation order). GPU times per pass go to
/// `timer` (stages "ds evaluate+error", "ds split", "ds scan", "ds compact").
DynamicSamplingResult dynamicSamplingGpu(const Scene& scene, const Volume& density,
                                         std::vector<RadianceSample> initial,
                                         DynamicSamplingGpuSteps steps,
                                         const DynamicSamplingSettings& settings,
                                         StageTimer* timer = nullptr,
                                         std::vector<std::vector<float>>* errors = nullptr);

/// Exclusive scan of 0/1 flags by compute shader (the scan used by dynamicSamplingGpu, on host
/// data: upload, scan, read back), for comparison with scatterlab::exclusiveScan. Returns the
/// total.
std::uint32_t exclusiveScanGpu(std::span<const std::uint8_t> flags,
                               std::span<std::uint32_t> offsets);

}  // namespace scatterlab::gpu
