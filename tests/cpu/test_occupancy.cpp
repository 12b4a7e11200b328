/// The occupancy mask (separable dilation) equals the per-voxel neighbourhood test.

#include <gtest/gtest.h>

#include <random>

#include "cpu/per_voxel.h"

using namespace scatterlab;

TEST(Occupancy, MaskEqualsNeighbourhoodTest) {
  std::mt19937 rng(3);
  const Box box{Vec3(-0.3f, 0.1f, 0.0f), Vec3(0.9f, 1.0f, 0.7f)};
  DensityGrid density(box, IVec3(23, 17, 11));
  for (float& d : density.data()) d = (rng() % 40 == 0) ? 1.0f : 0.0f;
  for (const IVec3 res : {IVec3(23, 17, 11), IVec3(12, 9, 6), IVec3(40, 30, 20)}) {
    const RadianceGrid radiance(box, res);
    const std::vector<char> mask = occupancyMask(density, radiance);
    const VoxelOccupancy test(density, radiance);
    long long occupied = 0;
    for (int k = 0; k < res.z; ++k)
      for (int j = 0; j < res.y; ++j)
        for (int i = 0; i < res.x; ++i) {
          ASSERT_EQ(bool(mask[radiance.index(i, j, k)]), test(i, j, k))
              << i << " " << j << " " << k;
          occupied += mask[radiance.index(i, j, k)];
        }
    EXPECT_GT(occupied, 0);
    EXPECT_LT(occupied, (long long)radiance.size());
  }
}
