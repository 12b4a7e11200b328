#include "core/max_density_grid.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

namespace scatterlab {

MaxDensityGrid::MaxDensityGrid(const DensityGrid& g) {
  const IVec3 d = g.dims();
  blocks_ = (d + (kBlock - 1)) / kBlock;
  max_.assign(std::size_t(blocks_.x) * blocks_.y * blocks_.z, 0.0f);
  // Block b covers index coordinates [b·B − 1, (b + 1)·B + 1) (the margin): their lookups read
  // voxels floor(u) and floor(u) + 1, i.e. [b·B − 1, (b + 1)·B + 1], clamped to the grid.
  const auto range = [&](int b, int a) {
    return IVec3(std::max(0, b * kBlock - 1), std::min(d[a] - 1, (b + 1) * kBlock + 1), 0);
  };
  tbb::parallel_for(tbb::blocked_range<int>(0, blocks_.z), [&](const tbb::blocked_range<int>& r) {
    for (int bz = r.begin(); bz < r.end(); ++bz) {
      const IVec3 rz = range(bz, 2);
      for (int by = 0; by < blocks_.y; ++by) {
        const IVec3 ry = range(by, 1);
        for (int bx = 0; bx < blocks_.x; ++bx) {
          const IVec3 rx = range(bx, 0);
          float m = 0.0f;
          for (int k = rz.x; k <= rz.y; ++k)
            for (int j = ry.x; j <= ry.y; ++j) {
              const float* p = &g.at(0, j, k);
              for (int i = rx.x; i <= rx.y; ++i) m = std::max(m, p[i]);
            }
          max_[(std::size_t(bz) * blocks_.y + by) * blocks_.x + bx] = m;
        }
      }
    }
  });
}

}  // namespace scatterlab
