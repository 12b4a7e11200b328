#include "render/per_voxel.h"

#include <tbb/parallel_for.h>

#include <atomic>

#include "render/volume_tracer.h"

namespace scatterlab {

PerVoxelStats buildPerVoxelRadiance(const Scene& scene, const DensityGrid& density, float delta1,
                                    RadianceGrid& radiance, Progress* progress) {
  const IVec3 nr = radiance.dims();
  const VoxelOccupancy occupied(density, radiance);
  const SourceRadiance source(scene, density, delta1);
  const Vec3 eye = scene.camera.position;
  std::atomic<long long> traced{0}, skipped{0};
  tbb::parallel_for(0, nr.z, [&](int k) {
    long long t = 0, s = 0;
    for (int j = 0; j < nr.y; ++j)
      for (int i = 0; i < nr.x; ++i) {
        const Vec3 c = radiance.cellCenter(i, j, k);
        if (!occupied(i, j, k)) {
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
