#pragma once
/// Whole methods on the GPU. Creating one needs no context; render() creates it (GpuError when
/// none can be made). Same image and stats keys as the CPU methods; backend "gpu", device =
/// GL_RENDERER; GPU milliseconds per pass (timer queries) in stats.extra["gpu_ms"]; the wall
/// `timings_ms` end each stage with glFinish.

#include <memory>
#include <optional>

#include "core/method.h"
#include "core/stages.h"
#include "render/methods.h"
#include "sampling/dynamic_sampling.h"

namespace scatterlab::gpu {

/// `per-voxel` on the GPU: density splat (or CPU build + upload) -> per-voxel S by compute ->
/// slice marcher -> read back. `raySteps`: slice marcher layers along each pixel's ray (see
/// SliceMarcher) instead of view planes.
std::unique_ptr<Method> makePerVoxelGpuMethod(const MarchParams& mp, IVec3 radianceResolution,
                                              bool raySteps, std::string backendNote);

/// What the sample-based GPU methods share.
struct SampledGpuConfig {
  MarchParams mp;
  IVec3 radianceResolution{0};
  float delta2 = 0.0f;  ///< central-difference step of ∇S
  bool raySteps = true;
  std::string samplerType;
  std::unique_ptr<Sampler> sampler;  ///< runs on the CPU (on the density read back)
  std::string backendNote;
};

/// `gradient` on the GPU: density on the GPU -> CPU sampler -> volume-tracer-gpu (S, ∇S) ->
/// gradient-gpu splatting -> slice marcher -> read back. Stages as the CPU method: density,
/// sampling, evaluation, reconstruction, march.
std::unique_ptr<Method> makeGradientGpuMethod(SampledGpuConfig config);

/// `adaptive` on the GPU: density on the GPU -> CPU sampler (initial samples) ->
/// dynamicSamplingGpu -> gradient-gpu -> slice marcher. Stages: density, sampling,
/// dynamic_sampling, reconstruction, march; the same per-level stats as the CPU method.
std::unique_ptr<Method> makeAdaptiveGpuMethod(SampledGpuConfig config,
                                              DynamicSamplingSettings settings);

}  // namespace scatterlab::gpu
