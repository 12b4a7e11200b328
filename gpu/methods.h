#pragma once
/// Whole methods on the GPU.

#include <memory>

#include "core/method.h"
#include "render/methods.h"

namespace scatterlab::gpu {

/// `per-voxel` on the GPU: density splat (or CPU build + upload) -> per-voxel S by compute ->
/// slice marcher -> read back. Same image and stats keys as the CPU method; backend "gpu",
/// device = GL_RENDERER; GPU milliseconds per pass in stats.extra["gpu_ms"]. Creating it needs
/// no context; render() creates one (GpuError when none can be made).
std::unique_ptr<Method> makePerVoxelGpuMethod(const MarchParams& mp, IVec3 radianceResolution,
                                              std::string backendNote);

}  // namespace scatterlab::gpu
