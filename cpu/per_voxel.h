#pragma once
/// The paper's baseline reconstruction (Kajiya & Von Herzen): trace S at every voxel centre of
/// the radiance volume. Also the reference the interpolation schemes are compared with.

#include <vector>
#include "core/grid.h"

#include "core/progress.h"
#include "core/scene.h"

namespace scatterlab {

/// Whether a radiance voxel can influence the image: the density volume is non-zero somewhere
/// in the trilinear support of the voxel (the marcher only looks S up where D > 0). Shared by
/// the per-voxel baseline (which skips the others) and the interpolating reconstructions
/// (which count occupied voxels no sample covers).
class VoxelOccupancy {
 public:
  /// References must outlive this object.
  VoxelOccupancy(const DensityGrid& density, const RadianceGrid& radiance)
      : density_(density),
        radiance_(radiance),
        hr_(radiance.cellSize()),
        scale_(density.indexScale()),
        offset_(density.indexOffset()),
        nd_(density.dims()) {}

  bool operator()(int i, int j, int k) const {
    const Vec3 c = radiance_.cellCenter(i, j, k);
    // Density voxels whose trilinear support overlaps this voxel's support: open intervals,
    // so the range is shrunk by 1e-4 voxel (a voxel exactly two centres away does not count,
    // whatever the rounding); on equal layouts this is the 3x3x3 neighbourhood.
    const IVec3 lo = glm::max(IVec3(glm::floor((c - hr_) * scale_ + offset_ + 1e-4f)), IVec3(0));
    const IVec3 hi = glm::min(IVec3(glm::ceil((c + hr_) * scale_ + offset_ - 1e-4f)), nd_ - 1);
    for (int kk = lo.z; kk <= hi.z; ++kk)
      for (int jj = lo.y; jj <= hi.y; ++jj)
        for (int ii = lo.x; ii <= hi.x; ++ii)
          if (density_.at(ii, jj, kk) > 0.0f) return true;
    return false;
  }

 private:
  const DensityGrid& density_;
  const RadianceGrid& radiance_;
  Vec3 hr_, scale_, offset_;
  IVec3 nd_;
};

/// VoxelOccupancy of every voxel of `radiance`, as a mask indexed like the grid (1 = occupied).
/// When the radiance volume has the density volume's layout (the usual case) the 3x3x3
/// neighbourhood test is a separable dilation of (D > 0). TBB-parallel.
std::vector<char> occupancyMask(const DensityGrid& density, const RadianceGrid& radiance);

struct PerVoxelStats {
  long long traced = 0;   ///< voxels whose S was traced
  long long skipped = 0;  ///< voxels left at 0: no density in their 2x2x2 neighbourhood
                          ///< (or, factored, no spot cone reaches it)
};

/// Fills `radiance` (bounds and dims set by the caller, normally those of `density`) with S at
/// each voxel centre, for light leaving towards the camera position (a pinhole camera sees each
/// point from one direction, so S is single-valued per point even for HG phase). A voxel whose
/// trilinear neighbourhood in the density volume is empty cannot contribute to the image and is
/// skipped; the result is identical to tracing it. TBB-parallel; no GL context.
/// `factored` (adaptive's whole-scene fallback, with PipelineSettings::factorLights): V = S / A
/// instead of S (FactoredSourceRadiance, A with the lamp model where `lampModel`), which the
/// factored march multiplies by A again; a voxel no spot cone reaches within its half-diagonal
/// is then skipped too (LitReach, shading/transport.h: A is 0 wherever the march reads it).
/// `simdShadows` (TracerSteps::simdShadows, render.fast_march): the shadow rays of
/// cpu/shadow_rays.h instead of the scalar opticalDepth.
PerVoxelStats buildPerVoxelRadiance(const Scene& scene, const DensityGrid& density, float delta1,
                                    RadianceGrid& radiance, Progress* progress,
                                    bool factored = false, bool lampModel = false,
                                    bool simdShadows = false);

}  // namespace scatterlab
