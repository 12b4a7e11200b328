#pragma once
/// Empty-space skipping on the GPU (issue 34): the twin of MaxDensityGrid
/// (core/max_density_grid.h), built on the GPU from a density volume and walked by the compute
/// view march (block_walk.glsl), so that the march jumps over the steps inside blocks of
/// kBlock³ voxels where every lookup returns exactly 0. Needs the GL context.

#include "gpu/gl.h"
#include "gpu/shaders.h"
#include "gpu/timer.h"
#include "gpu/volume.h"

namespace scatterlab::gpu {

/// Blocks per axis of `density`'s empty-space grid: ceil(dims / MaxDensityGrid::kBlock).
IVec3 blockCount(const Volume& density);

/// The R32F grid of `density`'s block maxima (MaxDensityGrid's definition: the largest density
/// a trilinear lookup within one voxel of the block can read), built by one compute pass
/// ("empty-space grid" in `timer`) on the first call for this volume and kept in
/// density.blockMax after that.
const Texture& blockMaxGrid(const Volume& density, StageTimer* timer);

/// Shadow rays (common.glsl opticalDepth) that jump over the steps in blocks of zero density:
/// they add exactly 0, so the optical depths are the plain sums bit for bit. Prepends
/// block_walk.glsl and defines SL_SKIP_SHADOWS; the pass calls TracingInputs::skipEmptySpace.
ProgramVariant& addShadowRaySkip(ProgramVariant& variant);

}  // namespace scatterlab::gpu
