#include "render/per_voxel.h"

#include <tbb/parallel_for.h>

#include <atomic>

#include "render/volume_tracer.h"

namespace scatterlab {

PerVoxelStats buildPerVoxelRadiance(const Scene& scene, const DensityGrid& density, float delta1,
                                    RadianceGrid& radiance, Progress* progress) {
  const IVec3 nr = radiance.dims(), nd = density.dims();
  const Vec3 hr = radiance.cellSize();
  const Vec3 dScale = density.indexScale(), dOffset = density.indexOffset();
  const SourceRadiance source(scene, density, delta1);
  const Vec3 eye = scene.camera.position;
  std::atomic<long long> traced{0}, skipped{0};
  tbb::parallel_for(0, nr.z, [&](int k) {
    long long t = 0, s = 0;
    for (int j = 0; j < nr.y; ++j)
      for (int i = 0; i < nr.x; ++i) {
        const Vec3 c = radiance.cellCenter(i, j, k);
        // Density voxels whose trilinear support overlaps this voxel's support.
        const IVec3 lo = glm::max(IVec3(glm::floor((c - hr) * dScale + dOffset)), IVec3(0));
        const IVec3 hi = glm::min(IVec3(glm::ceil((c + hr) * dScale + dOffset)), nd - 1);
        bool occupied = false;
        for (int kk = lo.z; kk <= hi.z && !occupied; ++kk)
          for (int jj = lo.y; jj <= hi.y && !occupied; ++jj)
            for (int ii = lo.x; ii <= hi.x; ++ii)
              if (density.at(ii, jj, kk) > 0.0f) {
                occupied = true;
                break;
              }
        if (!occupied) {
          radiance.at(i, j, k) = Vec3(0.0f);
          ++s;
          continue;
        }
        const Vec3 v = eye - c;
        const float len = glm::length(v);
        radiance.at(i, j, k) = source(c, len > 0.0f ? v / len : Vec3(0, 0, 1));
        ++t;
      }
    traced += t;
    skipped += s;
    if (progress) progress->advance(1);
  });
  return {traced.load(), skipped.load()};
}

}  // namespace scatterlab
