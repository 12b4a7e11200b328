/// The SIMD shadow rays of `exact` (cpu/shadow_rays.h) against the scalar opticalDepth of
/// shading/transport.h, and the `exact` image with them against the plain march's.

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <random>

#include "cpu/shadow_rays.h"
#include "shading/transport.h"
#include "support/scenes.h"

using namespace scatterlab;

namespace {

Scene glowScene(int res) {
  initialize();
  Scene s = loadScene(scatterlab::testing::kGlow);
  s.medium.resolution = IVec3(res);
  s.camera.width = 96;
  s.camera.height = 72;
  s.render = Json{{"method", "exact"}};
  return s;
}

/// Largest relative difference of the SIMD optical depth from the scalar one over random
/// segments through `g` (steps of 0.7, 1, 3 and 11 voxels of `voxel`), and how many crossed
/// density.
struct DepthComparison {
  double maxRel = 0.0;
  int nonzero = 0;
};
DepthComparison compareDepths(const DensityGrid& g, float voxel, ShadowKernel k) {
  const DensityLayout layout = densityLayout(g);
  std::mt19937 rng(11);
  std::uniform_real_distribution<float> u(-0.3f, 1.3f);
  DepthComparison c;
  for (int i = 0; i < 4000; ++i) {
    const Vec3 a(u(rng), u(rng), u(rng)), b(u(rng), u(rng), u(rng));
    const float steps[] = {0.7f, 1.0f, 3.0f, 11.0f};
    const float step = steps[i % 4] * voxel;
    const float plain = opticalDepth(g, a, b, step);
    const float simd = opticalDepthSimd(g, layout, a, b, step, kInfinity, k);
    if (plain == 0.0f) {
      EXPECT_EQ(simd, 0.0f) << i;
      continue;
    }
    ++c.nonzero;
    c.maxRel = std::max(c.maxRel, double(std::abs(simd - plain)) / plain);
  }
  return c;
}

}  // namespace

TEST(ShadowRays, SimdOpticalDepthMatchesTheScalarSum) {
  // The same lookups; only the order of the float sum (4 or 8 partial sums) and, with FMA,
  // the rounding of u0 + i·du differ. Measured max relative difference over the 2502 of 4000
  // segments that cross density: 5.1e-7 (sse2) and 5.9e-6 (avx2: FMA rounds u0 + i·du differently,
  // which moves lookups by an ulp of the index coordinate on short, thin segments).
  const Scene s = glowScene(45);
  const DensityGrid g = buildDensityVolume(s);
  for (const ShadowKernel k : {ShadowKernel::Sse2, ShadowKernel::Avx2, ShadowKernel::Best}) {
    if (k == ShadowKernel::Avx2 && std::string(shadowRayKernel()) != "avx2") continue;
    const DepthComparison c = compareDepths(g, 1.0f / 45.0f, k);
    EXPECT_GT(c.nonzero, 1000);
    std::printf("kernel %d: max relative difference %.3g over %d segments\n", int(k), c.maxRel,
                c.nonzero);
    EXPECT_LT(c.maxRel, k == ShadowKernel::Sse2 ? 8e-7 : 9e-6) << int(k);
  }
}

TEST(ShadowRays, FlatAndOddSizedVolumes) {
  // One voxel along an axis (neighbour offset 0) and sizes that are no multiple of a batch:
  // the same lookups as Grid3::sampleIndex. Measured max relative difference 7.3e-7.
  for (const IVec3 dims : {IVec3(13, 1, 7), IVec3(1, 9, 5), IVec3(6, 5, 1), IVec3(3, 3, 3)}) {
    DensityGrid g(Box{}, dims);
    std::mt19937 rng(3);
    std::uniform_real_distribution<float> v(0.0f, 2.0f);
    for (float& x : g.data()) x = v(rng);
    const DepthComparison c = compareDepths(g, 0.1f, ShadowKernel::Best);
    EXPECT_GT(c.nonzero, 1000);
    std::printf("%dx%dx%d: max relative difference %.3g\n", dims.x, dims.y, dims.z, c.maxRel);
    EXPECT_LT(c.maxRel, 1.1e-6) << dims.x << " " << dims.y << " " << dims.z;
  }
}

TEST(ShadowRays, CutoffStopsOnlyBeyondTheDepth) {
  // Where the whole segment's depth stays below the cutoff the result is the full sum; beyond
  // it, a depth past the cutoff (checked every 32 steps).
  const Scene s = glowScene(45);
  DensityGrid g = buildDensityVolume(s);
  for (float& x : g.data()) x *= 50.0f;
  const DensityLayout layout = densityLayout(g);
  const Vec3 a(0.5f, 0.5f, -0.2f), b(0.5f, 0.5f, 1.2f);
  const float step = 1.0f / 45.0f;
  const float full = opticalDepth(g, a, b, step);
  ASSERT_GT(full, 1.0f);
  const float cut = full * 0.3f;
  const float stopped = opticalDepthSimd(g, layout, a, b, step, cut);
  EXPECT_GE(stopped, cut);
  EXPECT_LT(stopped, full);
  EXPECT_NEAR(opticalDepthSimd(g, layout, a, b, step, full * 2.0f), full, 2e-6f * full);
}

TEST(ShadowRays, ExactImageMatchesThePlainMarch) {
  // render.fast_march (SIMD shadow rays, fast view march) against render.fast_march=false
  // (scalar shadow rays, plain march). Measured relative L2 1.0e-7 (view steps of 1 voxel)
  // and 7.6e-9 (11 voxels), AVX2 kernel.
  for (const float voxels : {1.0f, 11.0f}) {
    Scene s = glowScene(45);
    s.render["march_step"] = voxels / 45.0f;
    s.render["fast_march"] = true;
    const Image fast = createMethod(s)->render(s, nullptr).image;
    s.render["fast_march"] = false;
    const Image plain = createMethod(s)->render(s, nullptr).image;
    std::printf("view step %g voxels: relative L2 %.3g\n", voxels,
                compareImages(fast, plain).relL2);
    EXPECT_LT(compareImages(fast, plain).relL2, 1.5e-7) << voxels;
    EXPECT_GT(compareImages(plain, Image(plain.width(), plain.height())).relL2, 0.5);
  }
}
