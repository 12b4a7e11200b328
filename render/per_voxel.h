#pragma once
/// The paper's baseline reconstruction (Kajiya & Von Herzen): trace S at every voxel centre of
/// the radiance volume. Also the reference the interpolation schemes are compared with.

#include "core/progress.h"
#include "core/scene.h"

namespace scatterlab {

struct PerVoxelStats {
  long long traced = 0;   ///< voxels whose S was traced
  long long skipped = 0;  ///< voxels left at 0: no density in their 2x2x2 neighbourhood
};

/// Fills `radiance` (bounds and dims set by the caller, normally those of `density`) with S at
/// each voxel centre, for light leaving towards the camera position (a pinhole camera sees each
/// point from one direction, so S is single-valued per point even for HG phase). A voxel whose
/// trilinear neighbourhood in the density volume is empty cannot contribute to the image and is
/// skipped; the result is identical to tracing it. TBB-parallel; no GL context.
PerVoxelStats buildPerVoxelRadiance(const Scene& scene, const DensityGrid& density, float delta1,
                                    RadianceGrid& radiance, Progress* progress);

}  // namespace scatterlab
