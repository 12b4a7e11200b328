#pragma once
/// Shared pieces of the CPU methods and their registration.

#include "core/params.h"
#include "core/scene.h"
#include "core/stats.h"
#include "render/ray_marcher.h"

namespace scatterlab {

/// Step settings shared by the marching methods (render keys march_step, delta1,
/// min_transmittance; both steps default to one voxel edge of the medium volume).
struct MarchParams {
  MarchSettings march;
  float delta1 = 0.0f;  ///< volume-tracing step towards the lights (the paper's Δ1)
};
MarchParams parseMarchParams(Params& render, const Scene& scene);

/// render.radiance_resolution: int or [nx, ny, nz]; defaults to medium.resolution.
IVec3 parseRadianceResolution(Params& render, const Scene& scene);

/// Builds the medium's density volume at its resolution, timed as stage "density".
DensityGrid buildDensityVolume(const Scene& scene, RenderStats& stats);

/// Marches the camera rays through `density` with S looked up trilinearly in `radiance`, timed
/// as stage "march" (the integrator shared by every radiance-volume method on the CPU).
Image marchRadianceVolume(const Scene& scene, const DensityGrid& density,
                          const RadianceGrid& radiance, const MarchSettings& march,
                          RenderStats& stats, Progress* progress);

/// Registers `exact` and `per-voxel` in methods().
void registerReferenceMethods();

}  // namespace scatterlab
