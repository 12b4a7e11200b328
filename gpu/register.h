#pragma once
/// Registration of the GPU variants (called from scatterlab::initialize() when the library is
/// built with SCATTERLAB_GPU). Needs no GL context: contexts are made when a stage first runs.

#include <string>

namespace scatterlab::gpu {

/// Adds "volume-tracer-gpu", "gradient-gpu", "per-voxel-gpu" and "slice-marcher" to the stage
/// registries, and makes the `per-voxel`, `gradient` and `adaptive` methods dispatch to the GPU
/// for backend "gpu" (and "auto" when a hardware GPU is present); their GPU variants read the
/// extra render key `slicing` ("ray-steps" default | "view-planes"). Call after
/// registerReferenceMethods() and registerSampledMethods().
void registerGpuStages();

/// Resolves backend "auto": "gpu" when a context can be made on a hardware GPU (not a
/// software rasteriser), else "cpu"; "cpu" and "gpu" pass through. `why` says what was found.
/// May create the GL context.
std::string resolveBackend(const std::string& backend, std::string* why = nullptr);

}  // namespace scatterlab::gpu
