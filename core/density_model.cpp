#include "core/density_model.h"

#include <tbb/parallel_for.h>

namespace scatterlab {

void DensityModel::build(DensityGrid& grid) const {
  const IVec3 n = grid.dims();
  tbb::parallel_for(0, n.z, [&](int k) {
    for (int j = 0; j < n.y; ++j)
      for (int i = 0; i < n.x; ++i) grid.at(i, j, k) = eval(grid.cellCenter(i, j, k));
  });
}

Registry<DensityModelFactory>& densityModels() {
  static Registry<DensityModelFactory> r("density type");
  return r;
}

}  // namespace scatterlab
