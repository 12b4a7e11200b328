#pragma once
/// Registration of the GPU backend (called from scatterlab::initialize() when the library is
/// built with SCATTERLAB_GPU). Needs no GL context: contexts are made when a stage first runs.

namespace scatterlab::gpu {

/// Registers the GPU backend's frame (backends()) and the GPU variants beside the CPU ones:
/// evaluator "volume-tracer", reconstructions "gradient" and "per-voxel", integrator
/// "ray-marcher" (the slice marcher; slicing from PipelineSettings), integrators
/// "light-space-march" and "radial-blur" (gpu/light_space_march.h, gpu/radial_blur.h), refiner
/// "dynamic". Backend "auto" prefers the GPU only on hardware (not a software rasteriser).
void registerGpuStages();

}  // namespace scatterlab::gpu
