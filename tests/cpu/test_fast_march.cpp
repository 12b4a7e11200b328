/// The fast CPU march (render.fast_march: empty-space skipping over MaxDensityGrid, tiles,
/// fused density + radiance lookups) against the plain march it replaces.

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <random>

#include "core/max_density_grid.h"
#include "cpu/fused_march.h"
#include "cpu/fused_volume.h"
#include "shading/transport.h"
#include "support/scenes.h"

using namespace scatterlab;

namespace {

/// The glow's Gaussian smoke (mostly empty space) at `res`³, a small image.
Scene glowScene(int res, const std::string& method) {
  initialize();
  Scene s = loadScene(scatterlab::testing::kGlow);
  s.medium.resolution = IVec3(res);
  s.camera.width = 96;
  s.camera.height = 72;
  // gradient's samples, not the whole-scene fallback of a 40³ volume.
  s.render = scatterlab::testing::sampledPath(Json{{"method", method}});
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
  // per-voxel and gradient (factored lights) through the fused density + radiance lookup (the
  // SIMD kernels, cpu/fused_march.h, whichever this CPU runs): the same steps; S is looked
  // up at u0 + i·du instead of (r.at(t)·scale + offset), the same point up to rounding, the
  // lerps in another order (avx2: y, z, x with FMA) and exp as above; and the voxels' and
  // samples' shadow rays traced by cpu/shadow_rays.h (sums in 4 or 8 lanes, the cutoff).
  // Measured with the avx2 kernels: rel. L2 6.9e-7 per-voxel, 2.1e-7 gradient; alpha 2.4e-7
  // (two float ulps of 1).
  for (const std::string method : {"per-voxel", "gradient"}) {
    const Scene s = glowScene(40, method);
    const Image fast = render(s, true), plain = render(s, false);
    std::printf("%s fast vs plain rel L2 %.3g alpha %.3g\n", method.c_str(),
                compareImages(fast, plain).relL2, maxAlphaDifference(fast, plain));
    EXPECT_LT(compareImages(fast, plain).relL2, 1.1e-6) << method;
    EXPECT_LT(maxAlphaDifference(fast, plain), 3.6e-7f) << method;
  }
}

/// march_steps / march_steps_skipped: with min_transmittance 0 (no ray stops early) the fast
/// march's steps looked up plus jumped over are the plain march's, which jumps none (glow at
/// 40³, 96 × 72: 66 569 + 1 067 = 67 636 for each method).
TEST(FastMarch, StepsLookedUpAndSkippedAddUpToThePlainMarch) {
  for (const std::string method : {"exact", "per-voxel", "gradient"}) {
    Scene s = glowScene(40, method);
    s.render["min_transmittance"] = 0;
    const auto steps = [&](bool fast) {
      s.render["fast_march"] = fast;
      const RenderStats st = createMethod(s)->render(s, nullptr).stats;
      return std::array<long long, 2>{st.extra.at("march_steps").get<long long>(),
                                      st.extra.at("march_steps_skipped").get<long long>()};
    };
    const auto fast = steps(true), plain = steps(false);
    std::printf("%s: fast %lld looked up + %lld skipped, plain %lld\n", method.c_str(), fast[0],
                fast[1], plain[0]);
    EXPECT_EQ(plain[1], 0) << method;
    EXPECT_EQ(fast[0] + fast[1], plain[0]) << method;
    EXPECT_GT(fast[1], 0) << method;
  }
}

namespace {

/// A 23 x 17 x 19 fused volume: random density with a zero slab and random radiance.
struct RandomFused {
  DensityGrid d{Box{}, IVec3(23, 17, 19)};
  RadianceGrid r{Box{}, IVec3(23, 17, 19)};
  explicit RandomFused(unsigned seed) {
    std::mt19937 rng(seed);
    std::uniform_real_distribution<float> u(0.0f, 1.0f);
    for (std::size_t i = 0; i < d.size(); ++i) {
      d.data()[i] = i % 23 < 6 ? 0.0f : 3.0f * u(rng);
      r.data()[i] = Vec3(u(rng), 2.0f * u(rng), 0.5f * u(rng));
    }
  }
};

/// The plain march's sums (ray_marcher.h's `step`) over steps [0, n) with Grid3 lookups. With
/// `A` (and the ray in world space, `world`) S is multiplied by A(x, −dir) at each step's point
/// origin + (t0 + (i + ½)·dt)·dir where S ≠ 0: the factored march, as FusedLookup's one-step
/// lookup.
FusedMarchState plainSums(const RandomFused& g, const FusedRay& ray, int n,
                          const FusedMarchConstants& c, const LightFactor* A = nullptr,
                          const Ray* world = nullptr) {
  FusedMarchState s{{0, 0, 0}, 1.0f, 0.0f};
  for (int i = 0; i < n && s.T > c.minT; ++i) {
    const Vec3 u =
        Vec3(ray.u0[0], ray.u0[1], ray.u0[2]) + float(i) * Vec3(ray.du[0], ray.du[1], ray.du[2]);
    const float D = g.d.sampleIndex(u);
    if (D <= 0.0f) continue;
    Vec3 S = g.r.sampleIndex(u);
    if (A && S != Vec3(0.0f)) S *= A->overStep(*world, ray.t0 + (float(i) + 0.5f) * ray.dt, ray.dt);
    const float a = std::exp(-c.sigmaT * D * ray.dt);
    for (int k = 0; k < 3; ++k) s.L[k] += s.T * c.ratio * (1.0f - a) * S[k];
    s.wt += s.T * (1.0f - a) * (ray.t0 + (float(i) + 0.5f) * ray.dt);
    s.T *= a;
  }
  return s;
}

/// Largest relative difference of L, T and wt (relative to max(|b|, 1e-3)).
float stateDifference(const FusedMarchState& a, const FusedMarchState& b) {
  const auto rel = [](float x, float y) { return std::abs(x - y) / std::max(std::abs(y), 1e-3f); };
  float m = std::max(rel(a.T, b.T), rel(a.wt, b.wt));
  for (int k = 0; k < 3; ++k) m = std::max(m, rel(a.L[k], b.L[k]));
  return m;
}

}  // namespace

TEST(FusedMarch, LightsFactorAsLightFactor) {
  // The kernels' A (FusedLights, point and spot lights SIMD over a group of steps, directional
  // ones once per ray) against LightFactor's, step by step: two point lights (one inside the
  // box with the lamp model, one outside), a spot with a soft edge, a spot with a hard one
  // (inner = outer), a directional light; Henyey–Greenstein and isotropic. World rays of 40
  // steps through the lights' neighbourhood, each kernel against plainSums with A; largest
  // relative difference of L, T, wt over 2000 rays. Measured (GCC 12): 2.6e-6 for HG and
  // isotropic, sse2 and avx2 alike (the lookups' rounding, as KernelsMatchThePlainSums; A
  // scaled by 0.999 for the directional light alone gives 7e-4 and 1e-3).
  const RandomFused g(5);
  Scene scene;
  scene.medium.sigmaT = 4.0f;
  Light inside, outside, soft, hard, sun;
  inside.position = Vec3(0.5f, 0.45f, 0.55f);
  inside.intensity = Vec3(1.0f, 0.8f, 0.6f);
  outside.position = Vec3(1.6f, 0.3f, -0.4f);
  outside.intensity = Vec3(3.0f);
  soft.type = hard.type = Light::Type::Spot;
  soft.position = Vec3(0.2f, 1.3f, 0.5f);
  soft.direction = glm::normalize(Vec3(0.2f, -1.0f, 0.1f));
  soft.cosOuter = 0.8f;
  soft.cosInner = 0.9f;
  soft.intensity = Vec3(2.0f, 2.0f, 1.0f);
  hard.position = Vec3(0.9f, -0.3f, 0.4f);
  hard.direction = glm::normalize(Vec3(-0.3f, 1.0f, 0.2f));
  hard.cosOuter = hard.cosInner = 0.85f;
  sun.type = Light::Type::Directional;
  sun.direction = glm::normalize(Vec3(0.3f, -1.0f, 0.4f));
  sun.intensity = Vec3(0.7f, 0.7f, 0.9f);
  scene.lights = {inside, outside, soft, hard, sun};
  // The lamp model's k_l = σt·D(s_l) with D = 2 everywhere: m ≠ 1 for the light inside.
  const LampModel lamp(scene, Box{}, [](const Vec3&) { return 2.0f; });
  ASSERT_GT(lamp.k(0), 0.0f);
  ASSERT_EQ(lamp.k(1), 0.0f);
  const FusedMarchConstants c{0.9f, 0.7f, 1e-6f};
  const FusedVolume vol(g.d, g.r, false);
  for (const bool hg : {true, false}) {
    scene.medium.phase = hg ? Phase{Phase::Type::HenyeyGreenstein, 0.6f} : Phase{};
    const LightFactor A(scene, lamp);
    const FusedLights lights(scene, lamp);
    std::mt19937 rng(13);
    std::uniform_real_distribution<float> u(-2.0f, 24.0f), step(0.3f, 1.7f), dir(-1.0f, 1.0f),
        w(-0.3f, 1.3f);
    float worst[2] = {0.0f, 0.0f};
    for (int k = 0; k < 2000; ++k) {
      Vec3 d(dir(rng), dir(rng), dir(rng));
      d = glm::normalize(d) * step(rng);
      const FusedRay ray{{u(rng), u(rng) * 0.7f, u(rng) * 0.8f}, {d.x, d.y, d.z}, 0.05f, 0.03f};
      const Ray world{Vec3(w(rng), w(rng), w(rng)),
                      glm::normalize(Vec3(dir(rng), dir(rng), dir(rng)))};
      const Vec3 toViewer = -world.dir, a = lights.directional(toViewer);
      const FusedFactor f{&lights,
                          {world.origin.x, world.origin.y, world.origin.z},
                          {world.dir.x, world.dir.y, world.dir.z},
                          {toViewer.x, toViewer.y, toViewer.z},
                          {a.x, a.y, a.z}};
      const int n = 40;
      const FusedMarchState plain = plainSums(g, ray, n, c, &A, &world);
      for (const MarchSimd simd : {MarchSimd::Sse2, MarchSimd::Avx2}) {
        if (simd == MarchSimd::Avx2 && !cpuHasAvx2Kernel()) continue;
        FusedMarchState s{{0, 0, 0}, 1.0f, 0.0f};
        fusedSpanKernel(simd)(vol.view(), c, ray, 0, 11, s, &f);
        fusedSpanKernel(simd)(vol.view(), c, ray, 11, n, s, &f);
        float& m = worst[simd == MarchSimd::Avx2];
        m = std::max(m, stateDifference(s, plain));
      }
    }
    std::printf("%s: sse2 vs LightFactor %.3g, avx2 %.3g\n", hg ? "HG" : "isotropic", worst[0],
                worst[1]);
    EXPECT_LT(worst[0], 4e-6f) << hg;
    EXPECT_LT(worst[1], 4e-6f) << hg;
  }
}

TEST(FusedMarch, KernelsMatchThePlainSums) {
  // Random rays (steps of 0.3-1.7 voxels, inside and partly outside the index box, where the
  // lookups clamp) through a random volume: each kernel against the plain march's Grid3
  // lookups and std::exp, and the two kernels against each other; largest relative
  // difference of L, T, wt over 3000 rays of 40 steps. Measured (GCC 12): vs plain 2.7e-6, avx2
  // vs sse2 1.4e-6 (lerp order and FMA); half storage (the same halves) avx2 vs sse2 2.1e-6;
  // clang 14 (which contracts a * b + c into FMAs where GCC does not): half avx2 vs sse2 6.8e-6.
  const RandomFused g(3);
  std::mt19937 rng(11);
  std::uniform_real_distribution<float> u(-2.0f, 24.0f), step(0.3f, 1.7f), dir(-1.0f, 1.0f);
  const FusedMarchConstants c{0.9f, 0.7f, 1e-6f};
  for (const bool half : {false, true}) {
    const FusedVolume vol(g.d, g.r, half);
    float dPlain = 0.0f, dKernels = 0.0f;
    for (int k = 0; k < 3000; ++k) {
      Vec3 d(dir(rng), dir(rng), dir(rng));
      d = glm::normalize(d) * step(rng);
      const FusedRay ray{{u(rng), u(rng) * 0.7f, u(rng) * 0.8f}, {d.x, d.y, d.z}, 0.25f, 0.1f};
      const int n = 40;
      FusedMarchState s2{{0, 0, 0}, 1.0f, 0.0f};
      // In two runs, as the march calls it per block.
      fusedSpanKernel(MarchSimd::Sse2)(vol.view(), c, ray, 0, 13, s2, nullptr);
      fusedSpanKernel(MarchSimd::Sse2)(vol.view(), c, ray, 13, n, s2, nullptr);
      if (!half) dPlain = std::max(dPlain, stateDifference(s2, plainSums(g, ray, n, c)));
      if (cpuHasAvx2Kernel()) {
        FusedMarchState s8{{0, 0, 0}, 1.0f, 0.0f};
        fusedSpanKernel(MarchSimd::Avx2)(vol.view(), c, ray, 0, 5, s8, nullptr);
        fusedSpanKernel(MarchSimd::Avx2)(vol.view(), c, ray, 5, n, s8, nullptr);
        dKernels = std::max(dKernels, stateDifference(s8, s2));
        if (!half) dPlain = std::max(dPlain, stateDifference(s8, plainSums(g, ray, n, c)));
      }
    }
    std::printf("half %d: vs plain %.3g, avx2 vs sse2 %.3g\n", int(half), dPlain, dKernels);
    EXPECT_LT(dPlain, 4e-6f) << half;
    EXPECT_LT(dKernels, 1.0e-5f) << half;
  }
}

TEST(FusedMarch, HalfFloatVolumeError) {
  // render.half_float_volumes against float storage on the glow (per-voxel, 40³): half keeps
  // 11 significant bits. Measured rel. L2 1.0e-4 per-voxel, 7.1e-5 gradient; alpha 5.0e-5.
  for (const std::string method : {"per-voxel", "gradient"}) {
    Scene s = glowScene(40, method);
    const Image full = render(s, true);
    s.render["half_float_volumes"] = true;
    const Image half = render(s, true);
    const double e = compareImages(half, full).relL2;
    std::printf("%s half vs float: rel L2 %.3g alpha %.3g\n", method.c_str(), e,
                maxAlphaDifference(half, full));
    EXPECT_GT(e, 0.0) << method;  // the option does change the storage
    EXPECT_LT(e, 1.5e-4) << method;
    EXPECT_LT(maxAlphaDifference(half, full), 7.5e-5f) << method;
  }
}

TEST(FusedMarch, SimdKernelsGiveTheSameImage) {
  // render.march_simd sse2 against avx2 (where the CPU has it) on the glow, per-voxel and
  // gradient (the lights' factor multiplied into each group of steps by the kernels).
  // Measured rel. L2 8.6e-8 per-voxel, 7.2e-8 gradient; alpha 2.4e-7.
  if (!cpuHasAvx2Kernel()) GTEST_SKIP() << "no AVX2 + FMA + F16C";
  for (const std::string method : {"per-voxel", "gradient"}) {
    Scene s = glowScene(40, method);
    s.render["march_simd"] = "sse2";
    const Image a = render(s, true);
    s.render["march_simd"] = "avx2";
    const Image b = render(s, true);
    const double e = compareImages(b, a).relL2;
    std::printf("%s avx2 vs sse2 image rel L2 %.3g alpha %.3g\n", method.c_str(), e,
                maxAlphaDifference(a, b));
    EXPECT_LT(e, 1.3e-7) << method;
    EXPECT_LT(maxAlphaDifference(a, b), 3.6e-7f) << method;
  }
}

TEST(MarchScale, ScaleOneIsTheFullMarchAndReducedMarchesStayClose) {
  // render.march_scale 1 is today's march bit for bit; 2 and 4 march one ray per 2² / 4²
  // pixels and upsample depth-aware. The Fig. 3 plume, 160 x 120, per-voxel at 32³ (a pixel
  // is 5 times larger than at 800 x 600, so are the errors: 0.33 % and 1.0 % there, see
  // docs/benchmarks.md). Measured rel. L2 against full resolution: 3.99 % (2), 10.9 % (4).
  initialize();
  Scene s = loadScene(SCATTERLAB_SOURCE_DIR "/data/scenes/fig3.json");
  s.medium.resolution = IVec3(32);
  s.camera.width = 160;
  s.camera.height = 120;
  s.render = Json{{"method", "per-voxel"}};
  const Image full = render(s, true);
  s.render["march_scale"] = 1;
  const Image one = render(s, true);
  EXPECT_EQ(compareImages(one, full).relL2, 0.0);
  EXPECT_EQ(maxAlphaDifference(one, full), 0.0f);
  EXPECT_EQ(one.depth(), full.depth());
  for (const auto& [scale, bound] : {std::pair{2, 0.060}, std::pair{4, 0.164}}) {
    s.render["march_scale"] = scale;
    const Image low = render(s, true);
    const double e = compareImages(low, full).relL2;
    std::printf("march_scale %d: rel L2 %.3g alpha %.3g\n", scale, e,
                maxAlphaDifference(low, full));
    EXPECT_GT(e, 0.0) << scale;
    EXPECT_LT(e, bound) << scale;
  }
}

TEST(MarchScale, MissedPixelsGetTheBackgroundExactly) {
  // Pixels whose rays miss the medium box keep the background and alpha 0, as marched.
  Scene s = glowScene(24, "per-voxel");
  s.camera.width = 64;
  s.camera.height = 48;
  const Image full = render(s, true);
  s.render["march_scale"] = 4;
  const Image low = render(s, true);
  int missed = 0;
  for (std::size_t i = 0; i < full.alpha().size(); ++i)
    if (full.alpha()[i] == 0.0f && low.alpha()[i] == 0.0f) {
      ++missed;
      EXPECT_EQ(low.pixels()[i], full.pixels()[i]) << i;
    }
  EXPECT_GT(missed, 1000);  // measured 2302 of 3072
}
