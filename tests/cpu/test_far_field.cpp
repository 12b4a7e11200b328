/// A's far field on the CPU (cpu/far_field.h, FarFieldCache): the vertices it computes are the
/// ones a march step can read. Its images against every light exact, the fast march and a
/// Renderer's frames are in test_fidelity.cpp (LightFactorization.AsFarField*).

#include <gtest/gtest.h>

#include <cstdio>
#include <memory>
#include <random>
#include <vector>

#include "cpu/far_field.h"
#include "shading/transport.h"
#include "support/scenes.h"

using namespace scatterlab;

namespace {

/// A 32³ unit box with 7 point lights (one above the middle, six on a ring), isotropic: the
/// lights and the box of the tests (their densities are their own).
Scene lampBoxScene() {
  Json doc = scatterlab::testing::homogeneousBoxDoc(1.0f, 8.0f, 0.8f, Vec3(0.5f, 0.9f, 0.5f), 0.3f,
                                                    40, 30, 32);
  scatterlab::testing::addRingOfLamps(doc, 6, 0.3, 0.5, {0.5, 0.4, 0.3});
  return scatterlab::testing::sceneFromJson(doc);
}

}  // namespace

/// Where the trilinear density lookup is non-zero (the only points the march looks the grid up
/// at) the grid over the bricks with density gives what the grid over every brick gives, bit for
/// bit; and most vertices are not computed. The density: single voxels on the faces of 8³-voxel
/// bricks (voxel 8 is read by points of cell 7, in the brick before) and at the box's corners.
TEST(FarFieldCache, ComputesEveryVertexAStepWithDensityReads) {
  const Scene scene = lampBoxScene();
  DensityGrid density(scene.medium.bounds, scene.medium.resolution);
  const std::vector<IVec3> voxels = {
      {8, 15, 16}, {23, 8, 7}, {16, 23, 24}, {0, 0, 31}, {31, 31, 0}};
  for (const IVec3& v : voxels) density.at(v.x, v.y, v.z) = 1.0f;
  const LampModel lamp(scene, density);
  FarFieldCache sparse, full;
  long long sparseTerms = 0, fullTerms = 0;
  const auto shared = std::make_shared<const DensityGrid>(density);
  const FarField& s = sparse.update(scene, lamp, shared, 4.0f, &sparseTerms);
  // A density of other dimensions than the medium's cells: every brick counts as read.
  const auto other =
      std::make_shared<const DensityGrid>(scene.medium.bounds, scene.medium.resolution + IVec3(1));
  const FarField& f = full.update(scene, lamp, other, 4.0f, &fullTerms);
  std::printf("far field terms: %lld over the bricks with density, %lld over all\n", sparseTerms,
              fullTerms);
  EXPECT_EQ(fullTerms, 7LL * 33 * 33 * 33);  // 7 point lights at every vertex
  EXPECT_LT(2 * sparseTerms, fullTerms);
  // Points within two voxels of each non-zero voxel, and anywhere.
  std::mt19937 rng(3);
  std::uniform_real_distribution<float> u(0.0f, 1.0f), near(-2.0f, 2.0f);
  const float voxel = 1.0f / 32.0f;
  int withDensity = 0;
  for (int i = 0; i < 200000; ++i) {
    const IVec3 v = voxels[std::size_t(i) % voxels.size()];
    const Vec3 x =
        i % 2 ? Vec3(u(rng), u(rng), u(rng))
              : glm::clamp((Vec3(v) + 0.5f + Vec3(near(rng), near(rng), near(rng))) * voxel,
                           Vec3(0.0f), Vec3(1.0f));
    if (!(density.sample(x) > 0.0f)) continue;
    ++withDensity;
    ASSERT_EQ(s.lookup(x), f.lookup(x)) << x.x << " " << x.y << " " << x.z;
  }
  EXPECT_GT(withDensity, 10000);
}

/// The live bricks are kept with the density object they were found in: the same object again
/// (a frame that kept its density) keeps the grid; a new object — even one made where the first
/// was freed — is scanned anew, its new bricks computed as a fresh cache computes them.
TEST(FarFieldCache, KeepsTheBricksOfTheSameDensityObjectOnly) {
  const Scene scene = lampBoxScene();
  DensityGrid first(scene.medium.bounds, scene.medium.resolution);
  first.at(4, 4, 4) = 1.0f;
  const LampModel lamp(scene, first);
  FarFieldCache cache;
  auto a = std::make_shared<const DensityGrid>(first);
  long long built = 0, kept = 0, rebuilt = 0, fresh = 0;
  cache.update(scene, lamp, a, 4.0f, &built);
  cache.update(scene, lamp, a, 4.0f, &kept);
  EXPECT_GT(built, 0);
  EXPECT_EQ(kept, 0);
  a.reset();
  DensityGrid second = first;
  second.at(27, 27, 27) = 1.0f;  // a brick the first has no density in
  const auto b = std::make_shared<const DensityGrid>(second);
  const FarField& g = cache.update(scene, lamp, b, 4.0f, &rebuilt);
  FarFieldCache other;
  const FarField& h = other.update(scene, lamp, b, 4.0f, &fresh);
  EXPECT_GT(rebuilt, built);
  EXPECT_EQ(rebuilt, fresh);
  const Vec3 x = (Vec3(27.0f) + 0.5f) / Vec3(scene.medium.resolution);
  EXPECT_NE(h.lookup(x), Vec3(0.0f));
  EXPECT_EQ(g.lookup(x), h.lookup(x));
}
