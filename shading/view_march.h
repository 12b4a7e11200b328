#pragma once
/// The ray-marcher's own keys (an integrator; its CPU variant in cpu/integrators.cpp, its GPU
/// variants in gpu/register.cpp): how the CPU's fast march stores and steps through the fused
/// volume, and how the GPU's raster marcher lays its slices. The view march itself (step,
/// transmittance cut-off, fast_march, march_scale) reads the keys every view-marching
/// integrator shares (MarchSettings in core/stages.h).

#include "core/stages.h"

namespace scatterlab {

/// render.march_simd: which compiled kernel the CPU's fast march runs (cpu/fused_march.h).
enum class MarchSimd { Auto, Sse2, Avx2 };

/// render.slicing: how the GPU's raster marcher lays its slices (the CPU marcher and the compute
/// pipeline step along each ray and have no slices).
enum class Slicing {
  RaySteps,    ///< layer k = step k of each pixel's own ray: the CPU marcher's sample points
  ViewPlanes,  ///< the paper's slabs perpendicular to the view axis
};

/// The ray-marcher's keys, in PipelineSettings::integratorKeys (rayMarcherStage()).
struct RayMarcherSettings {
  /// render.half_float_volumes: the CPU's fast march stores its fused density + radiance volume
  /// in IEEE half.
  bool halfFloat = false;
  MarchSimd simd = MarchSimd::Auto;     ///< render.march_simd
  Slicing slicing = Slicing::RaySteps;  ///< render.slicing (GPU raster pipeline only)
};

/// `ray-marcher`'s declaration: its keys half_float_volumes, march_simd (CPU) and slicing (GPU
/// raster) into PipelineSettings::integratorKeys (RayMarcherSettings); it marches the view rays
/// and, on the CPU, fuses the density and radiance volumes.
const StageDecl& rayMarcherStage();

}  // namespace scatterlab
