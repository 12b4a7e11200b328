/// The fast CPU march (render.fast_march: empty-space skipping over MaxDensityGrid, tiles,
/// fused density + radiance lookups) against the plain march it replaces.

#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "core/max_density_grid.h"
#include "core/transport.h"
#include "support/scenes.h"

using namespace scatterlab;

namespace {

/// The glow's Gaussian smoke (mostly empty space) at `res`³, a small image.
Scene glowScene(int res, const std::string& method) {
  initialize();
  Scene s = loadScene(SCATTERLAB_SOURCE_DIR "/data/scenes/glow.json");
  s.medium.resolution = IVec3(res);
  s.camera.width = 96;
  s.camera.height = 72;
  s.render = Json{{"method", method}};
  return s;
}

/// Largest |alpha difference| of two images of the same size.
float maxAlphaDifference(const Image& a, const Image& b) {
  float m = 0.0f;
  for (std::size_t i = 0; i < a.alpha().size(); ++i)
    m = std::max(m, std::abs(a.alpha()[i] - b.alpha()[i]));
  return m;
}

Image render(Scene s, bool fast) {
  s.render["fast_march"] = fast;
  return createMethod(s)->render(s, nullptr).image;
}

}  // namespace

TEST(MaxDensityGrid, BlocksHoldTheLookupsMaximum) {
  // 20 x 9 x 17 voxels: blocks of 8 with partial edge blocks; one non-zero voxel.
  DensityGrid g(Box{}, IVec3(20, 9, 17));
  g.at(8, 4, 16) = 2.0f;
  const MaxDensityGrid m(g);
  EXPECT_EQ(m.blocks(), IVec3(3, 2, 3));
  // Voxel x = 8 is read by lookups with u.x in (7, 9), within one voxel of blocks 0 and 1.
  EXPECT_EQ(m.max(IVec3(0, 0, 2)), 2.0f);
  EXPECT_EQ(m.max(IVec3(1, 0, 2)), 2.0f);
  EXPECT_EQ(m.max(IVec3(2, 0, 2)), 0.0f);
  EXPECT_EQ(m.max(IVec3(1, 1, 2)), 0.0f);  // y = 4 is three voxels from block 1 (y >= 8)
  EXPECT_EQ(m.max(IVec3(1, 0, 1)), 2.0f);  // z = 16 is the first voxel of block 2, next to 1
  EXPECT_EQ(m.max(IVec3(1, 0, 0)), 0.0f);
}

TEST(MaxDensityGrid, SkippingLeavesOpticalDepthUnchanged) {
  // Random segments through the glow's sparse density at a size that is not a multiple of the
  // block: the skipped sum is the plain sum, bit for bit (the skipped lookups are exactly 0).
  Scene s = glowScene(45, "exact");
  const DensityGrid g = buildDensityVolume(s);
  const MaxDensityGrid m(g);
  std::mt19937 rng(7);
  std::uniform_real_distribution<float> u(-0.3f, 1.3f);
  int nonzero = 0, skipped = 0;
  for (int i = 0; i < 4000; ++i) {
    const Vec3 a(u(rng), u(rng), u(rng)), b(u(rng), u(rng), u(rng));
    // Steps of 0.7, 1 and 11 voxels (longer than a block: blocks crossed between steps).
    const float step = (i % 3 == 0 ? 0.7f : i % 3 == 1 ? 1.0f : 11.0f) / 45.0f;
    const float plain = opticalDepth(g, a, b, step);
    ASSERT_EQ(opticalDepth(g, m, a, b, step), plain) << i;
    nonzero += plain > 0.0f;
  }
  for (int z = 0; z < m.blocks().z; ++z)
    for (int y = 0; y < m.blocks().y; ++y)
      for (int x = 0; x < m.blocks().x; ++x) skipped += m.max(IVec3(x, y, z)) == 0.0f;
  EXPECT_GT(nonzero, 1000);  // the segments do cross the smoke
  EXPECT_GT(skipped, 20);    // and there are empty blocks to skip (of 6³)
}

TEST(FastMarch, ExactImageMatchesThePlainMarch) {
  // Same steps summed in the same order; exp of four steps at once (xsimd, within an ulp of
  // std::exp); shadow rays stop at σt·τ = 25 (a transmittance of 1.4e-11). Also with view
  // steps of 11 voxels, longer than a block. Measured rel. L2 1.2e-7 (1 voxel), 2.8e-9 (11),
  // alpha 1.2e-7 (one float ulp of 1).
  for (const float voxels : {1.0f, 11.0f}) {
    Scene s = glowScene(45, "exact");
    s.render["march_step"] = voxels / 45.0f;
    const Image fast = render(s, true), plain = render(s, false);
    EXPECT_LT(compareImages(fast, plain).relL2, 2e-7) << voxels;
    EXPECT_LT(maxAlphaDifference(fast, plain), 2e-7f) << voxels;
    EXPECT_GT(compareImages(plain, Image(plain.width(), plain.height())).relL2, 0.5);  // not black
  }
}

TEST(FastMarch, VolumeLookupMatchesThePlainMarch) {
  // per-voxel and gradient (factored lights) through the fused density + radiance lookup: the
  // same steps; S is looked up at u0 + i·du instead of (r.at(t)·scale + offset), the same
  // point up to rounding, and exp as above (measured rel. L2 6.7e-7 per-voxel, 2.4e-7
  // gradient; alpha 1.2e-7).
  for (const std::string method : {"per-voxel", "gradient"}) {
    const Scene s = glowScene(40, method);
    const Image fast = render(s, true), plain = render(s, false);
    EXPECT_LT(compareImages(fast, plain).relL2, 1.1e-6) << method;
    EXPECT_LT(maxAlphaDifference(fast, plain), 2e-7f) << method;
  }
}
