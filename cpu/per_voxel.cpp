#include "cpu/per_voxel.h"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <atomic>

#include "cpu/shadow_rays.h"
#include "shading/transport.h"

namespace scatterlab {

std::vector<char> occupancyMask(const DensityGrid& density, const RadianceGrid& out) {
  const IVec3 n = out.dims();
  const std::size_t nxy = std::size_t(n.x) * n.y;
  std::vector<char> occ(out.size(), 0);
  const bool sameLayout = n == density.dims() && out.bounds().min == density.bounds().min &&
                          out.bounds().max == density.bounds().max;
  if (!sameLayout) {
    const VoxelOccupancy test(density, out);
    tbb::parallel_for(0, n.z, [&](int k) {
      for (int j = 0; j < n.y; ++j)
        for (int i = 0; i < n.x; ++i) occ[out.index(i, j, k)] = test(i, j, k);
    });
    return occ;
  }
  // (D > 0), then OR with the neighbours along x, y and z. Boundary rows read a zero row, so
  // the inner loops have no branches and vectorise.
  std::vector<char> tmp(out.size(), 0);
  const std::vector<char> zeros(std::max<std::size_t>(nxy, 1), 0);
  const float* d = density.data().data();
  const int nx = n.x;
  tbb::parallel_for(0, n.z, [&](int k) {
    for (int j = 0; j < n.y; ++j) {
      const std::size_t row = std::size_t(k) * nxy + std::size_t(j) * nx;
      char* t = tmp.data() + row;
      for (int i = 0; i < nx; ++i) t[i] = d[row + i] > 0.0f;
      char* o = occ.data() + row;
      o[0] = t[0] | (nx > 1 ? t[1] : 0);
      for (int i = 1; i + 1 < nx; ++i) o[i] = t[i - 1] | t[i] | t[i + 1];
      if (nx > 1) o[nx - 1] = t[nx - 2] | t[nx - 1];
    }
  });
  tbb::parallel_for(0, n.z, [&](int k) {
    for (int j = 0; j < n.y; ++j) {
      const std::size_t row = std::size_t(k) * nxy + std::size_t(j) * nx;
      const char* c = occ.data() + row;
      const char* lo = j > 0 ? c - nx : zeros.data();
      const char* hi = j + 1 < n.y ? c + nx : zeros.data();
      char* t = tmp.data() + row;
      for (int i = 0; i < nx; ++i) t[i] = c[i] | lo[i] | hi[i];
    }
  });
  tbb::parallel_for(0, n.z, [&](int k) {
    const char* c = tmp.data() + std::size_t(k) * nxy;
    const char* lo = k > 0 ? c - nxy : zeros.data();
    const char* hi = k + 1 < n.z ? c + nxy : zeros.data();
    char* o = occ.data() + std::size_t(k) * nxy;
    for (std::size_t a = 0; a < nxy; ++a) o[a] = c[a] | lo[a] | hi[a];
  });
  return occ;
}

namespace {

/// `lit` (null: none): voxels it does not reach within their half-diagonal are skipped too.
template <class Source>
PerVoxelStats tracePerVoxel(const Scene& scene, const DensityGrid& density, const Source& source,
                            RadianceGrid& radiance, Progress* progress,
                            const LitReach* lit = nullptr) {
  const IVec3 nr = radiance.dims();
  const std::vector<char> occupied = occupancyMask(density, radiance);
  const float reach = glm::length(radiance.cellSize());
  const Vec3 eye = scene.camera.position;
  std::atomic<long long> traced{0}, skipped{0};
  tbb::parallel_for(0, nr.z, [&](int k) {
    long long t = 0, s = 0;
    for (int j = 0; j < nr.y; ++j)
      for (int i = 0; i < nr.x; ++i) {
        const Vec3 c = radiance.cellCenter(i, j, k);
        if (!occupied[radiance.index(i, j, k)] || (lit && !lit->reaches(c, reach))) {
          radiance.at(i, j, k) = Vec3(0.0f);
          ++s;
          continue;
        }
        radiance.at(i, j, k) = source(c, towardsEye(eye, c));
        ++t;
      }
    traced += t;
    skipped += s;
    if (progress) progress->advance(1);
  });
  return {traced.load(), skipped.load()};
}

}  // namespace

PerVoxelStats buildPerVoxelRadiance(const Scene& scene, const DensityGrid& density, float delta1,
                                    RadianceGrid& radiance, Progress* progress, bool factored,
                                    bool lampModel, bool simdShadows) {
  const SimdShadowRays shadows(density);
  const ShadowDepthFn shadow = simdShadows ? shadows.fn() : ShadowDepthFn{};
  if (factored) {
    // V is multiplied by A in the march: where no spot cone reaches a voxel's support, nothing.
    const LitReach lit(scene.lights);
    return tracePerVoxel(scene, density,
                         FactoredSourceRadiance(scene, density, delta1, lampModel, shadow),
                         radiance, progress, lit.everywhere() ? nullptr : &lit);
  }
  return tracePerVoxel(scene, density,
                       SourceRadiance(scene, density, delta1, nullptr, simdShadows, shadow),
                       radiance, progress);
}

}  // namespace scatterlab
