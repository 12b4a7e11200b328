/// GPU dynamic sampling, scan and the gradient / adaptive methods against their CPU twins
/// (issues 5 and 6), on llvmpipe in CI with tiny scenes.

#include <bit>
#include <cstdint>
#include <random>

#include "core/stages.h"
#include "cpu/radiance_evaluator.h"
#include "gpu/dispatch.h"
#include "gpu/dynamic_sampling.h"
#include "gpu/reconstructions.h"
#include "gpu/slice_marcher.h"
#include "gpu/tracing.h"
#include "gpu/volume.h"
#include "gpu/volume_tracer.h"
#include "gpu_support.h"
#include "sampling/dynamic_sampling.h"
#include "sampling/scan.h"
#include "shading/transport.h"

namespace scatterlab::testing {
namespace {

void expectNoGlError() {
  EXPECT_EQ(glGetError(), GLenum(GL_NO_ERROR));
}

TEST(GpuScan, EqualsCpuScanOnRandomFlags) {
  SCATTERLAB_REQUIRE_GPU();
  std::mt19937 rng(11);
  // One block, block edges, several blocks, and three levels of block sums (> 512² elements).
  for (std::size_t n : {1u, 7u, 511u, 512u, 513u, 1024u, 4097u, 100000u, 262151u}) {
    for (double p : {0.0, 0.03, 0.5, 1.0}) {
      std::bernoulli_distribution flip(p);
      std::vector<std::uint8_t> flags(n);
      for (auto& f : flags) f = flip(rng) ? std::uint8_t(1 + rng() % 3) : 0;  // non-zero = 1
      std::vector<std::uint32_t> cpu(n), gpu(n);
      const std::uint32_t tc = exclusiveScan(flags, cpu);
      const std::uint32_t tg = gpu::exclusiveScanGpu(flags, gpu);
      expectNoGlError();
      EXPECT_EQ(tg, tc) << "n " << n << " p " << p;
      EXPECT_TRUE(cpu == gpu) << "n " << n << " p " << p;
    }
  }
}

/// A uniform slab lit by a narrow spot light (a shaft), 24³, tiny image.
Scene spotScene(int width = 32, int height = 24) {
  const Json doc{{"medium",
                  {{"bounds", {{"min", {0, 0, 0}}, {"max", {1, 1, 1}}}},
                   {"density", {{"type", "uniform"}, {"value", 1.0}}},
                   {"resolution", 24},
                   {"sigma_t", 1.2},
                   {"albedo", 0.6},
                   {"phase", {{"type", "isotropic"}}}}},
                 {"lights", Json::array({{{"type", "spot"},
                                          {"position", {0.35, 1.15, 0.5}},
                                          {"direction", {0.3, -1, 0.05}},
                                          {"intensity", {14, 13, 11}},
                                          {"inner_deg", 9},
                                          {"outer_deg", 12}}})},
                 {"camera",
                  {{"position", {0.5, 0.5, -1.6}},
                   {"look_at", {0.5, 0.5, 0.5}},
                   {"fov_y_deg", 40},
                   {"width", width},
                   {"height", height}}},
                 {"render", {{"method", "adaptive"}}}};
  return sceneFromJson(doc);
}

/// Initial samples on a 4³ lattice, radius = the lattice interval.
std::vector<RadianceSample> latticeSamples() {
  std::vector<RadianceSample> s;
  for (int k = 0; k < 4; ++k)
    for (int j = 0; j < 4; ++j)
      for (int i = 0; i < 4; ++i) {
        RadianceSample r;
        r.position = (Vec3(i, j, k) + 0.5f) / 4.0f;
        r.radius = 0.25f;
        s.push_back(r);
      }
  return s;
}

/// Under a budget a level splits its candidates from the worst error group down to a cut
/// (errorBin(): groups of 1/64 of an octave). A GPU's E differs from the CPU's by rounding (on an
/// H200 60–120× more than on llvmpipe), so an E next to the edge between the highest group left
/// unsplit and the next may cross it there. The samples of the levels the budget capped whose E
/// lies within `margin`, relative, of that edge (the highest unsplit group is that of maxLeft, a
/// capped candidate's E). `errors`: each split level's E, as dynamicSamplingGpu returns them.
long long nearACut(const DynamicSamplingResult& cpu, const std::vector<std::vector<float>>& errors,
                   double margin) {
  const double threshold = cpu.levels[0].threshold;
  const auto key = [](float x) { return std::bit_cast<std::uint32_t>(x) >> kErrorBinShift; };
  long long n = 0;
  for (std::size_t k = 0; k < errors.size() && k < cpu.levels.size(); ++k) {
    const LevelStats& l = cpu.levels[k];
    if (l.capped == 0) continue;
    const int g = errorBin(l.maxLeft, threshold);
    const float edge =
        std::bit_cast<float>((key(float(threshold)) + std::uint32_t(g) + 1u) << kErrorBinShift);
    for (const float e : errors[k])
      n += double(e) > threshold && std::abs(double(e) / double(edge) - 1.0) < margin;
  }
  return n;
}

/// Whether the GPU's pass made the CPU's decisions (every level's counts, the final count).
/// Where it did not, the difference must be one that rounding of E explains (issue 33 item 4):
/// some E within 1e-3 of a cut's edge (nearACut), and no level's splits off by more than those;
/// the caller then skips its sample-by-sample comparison.
bool sameDecisions(const DynamicSamplingResult& g, const DynamicSamplingResult& cpu,
                   const std::vector<std::vector<float>>& errors) {
  bool same = g.levels.size() == cpu.levels.size() && g.samples.size() == cpu.samples.size();
  for (std::size_t l = 0; same && l < cpu.levels.size(); ++l)
    same = g.levels[l].samples == cpu.levels[l].samples &&
           g.levels[l].split == cpu.levels[l].split && g.levels[l].capped == cpu.levels[l].capped &&
           g.levels[l].toppedUp == cpu.levels[l].toppedUp;
  if (same) return true;
  const long long mayFlip = nearACut(cpu, errors, 1e-3);
  std::printf("the GPU's decisions differ from the CPU's; %lld E within 1e-3 of a cut's edge\n",
              mayFlip);
  EXPECT_GT(mayFlip, 0) << "the decisions differ, and no E lies near a cut";
  EXPECT_EQ(g.levels.size(), cpu.levels.size());
  for (std::size_t l = 0; l < std::min(g.levels.size(), cpu.levels.size()); ++l)
    EXPECT_LE(std::abs(g.levels[l].split - cpu.levels[l].split), mayFlip) << "level " << l;
  return false;
}

TEST(GpuDynamicSampling, SameSampleSetAsCpu) {
  SCATTERLAB_REQUIRE_GPU();
  const Scene scene = spotScene();
  DensityGrid density(scene.medium.bounds, scene.medium.resolution);
  scene.medium.density->build(density);
  DynamicSamplingSettings ds;
  ds.levels = {8, 12};
  ds.delta1 = 1.0f / 24;
  // ε chosen so that no E of any evaluated sample lies within 1e-3 relative of it (checked
  // below on the GPU errors), so float differences between CPU and GPU cannot flip a flag.
  ds.epsilon = 2e-4;
  const float delta1 = 1.0f / 24, delta2 = 1.0f / 24;
  PipelineSettings ps;
  ps.delta1 = delta1;
  ps.delta2 = delta2;
  auto cpuEval = radianceEvaluators().get("volume-tracer", "evaluator").on[int(Backend::Cpu)](ps);
  const DynamicSamplingResult cpu = dynamicSampling(scene, density, latticeSamples(), *cpuEval, ds);

  const gpu::Volume d = gpu::uploadDensity(density);
  std::vector<std::vector<float>> errors;
  const DynamicSamplingResult g =
      gpu::dynamicSamplingGpu(scene, d, latticeSamples(), {delta1, delta2}, ds, nullptr, &errors);
  expectNoGlError();

  double closest = 1e30;
  for (const auto& level : errors)
    for (float e : level) closest = std::min(closest, std::abs(double(e) / ds.epsilon - 1.0));
  std::printf("closest E to epsilon: %.3g relative\n", closest);
  EXPECT_GT(closest, 1e-3) << "choose another epsilon: a flag may flip by rounding";

  ASSERT_EQ(g.levels.size(), cpu.levels.size());
  for (std::size_t l = 0; l < cpu.levels.size(); ++l) {
    EXPECT_EQ(g.levels[l].samples, cpu.levels[l].samples) << "level " << l;
    EXPECT_EQ(g.levels[l].split, cpu.levels[l].split) << "level " << l;
    EXPECT_NEAR(g.levels[l].maxError, cpu.levels[l].maxError, 1e-3 * cpu.levels[l].maxError);
  }
  // The scene must exercise splitting at every level.
  EXPECT_GT(cpu.levels[0].split, 0);
  EXPECT_GT(cpu.levels[1].split, 0);
  ASSERT_EQ(g.samples.size(), cpu.samples.size());
  float sMax = 0;
  for (const auto& s : cpu.samples) sMax = std::max(sMax, glm::length(s.S));
  int bad = 0;
  for (std::size_t i = 0; i < cpu.samples.size(); ++i) {
    const RadianceSample &a = g.samples[i], &b = cpu.samples[i];
    if (a.position != b.position || a.level != b.level || a.radius != b.radius) {
      if (++bad < 5)
        ADD_FAILURE() << "sample " << i << ": gpu (" << a.position.x << "," << a.position.y << ","
                      << a.position.z << ") r " << a.radius << " level " << a.level << " vs cpu ("
                      << b.position.x << "," << b.position.y << "," << b.position.z << ") r "
                      << b.radius << " level " << b.level;
    }
    for (int c = 0; c < 3; ++c)
      EXPECT_LE(std::abs(a.S[c] - b.S[c]), 1e-3f * (std::abs(b.S[c]) + 1e-2f * sMax))
          << "S of sample " << i;
  }
  EXPECT_EQ(bad, 0);
  std::printf("dynamic sampling: %zu samples, per level evaluated", cpu.samples.size());
  for (const auto& l : cpu.levels) std::printf(" %lld", l.samples);
  std::printf("\n");
}

/// Eq. 5 with 40 probes and 24 lamps inside a 96³ fog: E of every sample as the CPU computes it.
/// One invocation per sample traced ≈ 40 probes × 24 lights × ~80 steps ≈ 77k loop iterations,
/// past the 65535 after which llvmpipe ends every loop of an invocation (gallivm's
/// LP_MAX_TGSI_LOOP_ITERATIONS): half of each 16 samples then had a different E, and lamps32 split
/// 195 level-0 samples on the GPU against 332 on the CPU. The probe pass traces kProbeGroup probes
/// per invocation; a real GPU has no such limit, the test holds there too.
TEST(GpuDynamicSampling, ManyLightsFortyProbesErrorsAsOnCpu) {
  SCATTERLAB_REQUIRE_GPU();
  Json lights = Json::array();
  for (int i = 0; i < 24; ++i)
    lights.push_back({{"type", "point"},
                      {"position", {0.04 + 0.04 * i, 0.93, 0.06 + 0.035 * (i % 5)}},
                      {"intensity", {0.3, 0.25, 0.2}}});
  const Json doc{{"medium",
                  {{"bounds", {{"min", {0, 0, 0}}, {"max", {1, 1, 1}}}},
                   {"density", {{"type", "height"}, {"bottom", 1.0}, {"top", 0.3}}},
                   {"resolution", 96},
                   {"sigma_t", 1.5},
                   {"albedo", 0.8},
                   {"phase", {{"type", "isotropic"}}}}},
                 {"lights", lights},
                 {"camera",
                  {{"position", {0.5, 0.5, -1.6}},
                   {"look_at", {0.5, 0.5, 0.5}},
                   {"fov_y_deg", 40},
                   {"width", 8},
                   {"height", 6}}},
                 {"render", {{"method", "adaptive"}}}};
  const Scene scene = sceneFromJson(doc);
  DensityGrid density(scene.medium.bounds, scene.medium.resolution);
  scene.medium.density->build(density);
  DynamicSamplingSettings ds;
  ds.levels = {8};
  ds.epsilon = 1e30;  // no splits: level 0's errors are compared
  ds.probes = 40;
  ds.delta1 = scene.medium.voxelSize();
  ds.space.bounds = TaylorBounds{0.0f, 1.0f};
  const TracerSteps steps{ds.delta1, ds.delta1, /*factorLights=*/true, /*logSpace=*/false};
  const std::vector<RadianceSample> initial = latticeSamples();
  const gpu::Volume d = gpu::uploadDensity(density);
  std::vector<RadianceSample> s = initial;
  evaluateSamples(scene, density, steps, s, /*gradients=*/true);
  // Unweighted (error_weight "transmittance") and weighted by A at each probe ("radiance", the
  // default with factor_lights: SL_WEIGHT_A); and weighted with the probes' signed bias added
  // (bias_weight 3: SL_ERROR_BIAS).
  const LightFactor A(scene);
  struct Case {
    bool weighted;
    float bias;
  };
  for (const Case c : {Case{false, 0.0f}, Case{true, 0.0f}, Case{true, 3.0f}}) {
    const bool weighted = c.weighted;
    ds.space.weightA = weighted;
    ds.biasWeight = c.bias;
    std::vector<std::vector<float>> errors;
    gpu::dynamicSamplingGpu(scene, d, initial, steps, ds, nullptr, &errors);
    expectNoGlError();
    ASSERT_EQ(errors.size(), 1u);
    ASSERT_EQ(errors[0].size(), initial.size());
    double worst = 0.0, raised = 0.0;
    for (std::size_t j = 0; j < s.size(); ++j) {
      Vec3 p[kMaxProbes], S[kMaxProbes], probeA[kMaxProbes];
      float D[kMaxProbes];
      probePoints(s[j], p, ds.probes);
      std::vector<RadianceSample> probes(std::size_t(ds.probes));
      for (int i = 0; i < ds.probes; ++i) probes[std::size_t(i)].position = p[i];
      evaluateSamples(scene, density, steps, probes, /*gradients=*/false);
      for (int i = 0; i < ds.probes; ++i) {
        S[i] = probes[std::size_t(i)].S;
        D[i] = density.sample(p[i]);
        probeA[i] = lightFactorTowardsEye(A, p[i], scene.camera.position);
      }
      const float tau =
          std::exp(-scene.medium.sigmaT *
                   opticalDepth(density, s[j].position, scene.camera.position, ds.delta1));
      const float cpu = localShadingError(s[j], S, D, tau, ds.probes, ds.space,
                                          weighted ? probeA : nullptr, c.bias);
      ASSERT_GT(cpu, 0.0f) << "sample " << j;
      worst = std::max(worst, std::abs(double(errors[0][j]) / cpu - 1.0));
      const float plain =
          localShadingError(s[j], S, D, tau, ds.probes, ds.space, weighted ? probeA : nullptr);
      raised = std::max(raised, double(cpu) / double(plain));
    }
    std::printf(
        "24 lamps, 40 probes, weighted by A %d, bias weight %g: worst relative E difference "
        "%.3g, E raised up to %.3gx\n",
        int(weighted), double(c.bias), worst, raised);
    if (c.bias > 0.0f) {
      EXPECT_GT(raised, 1.5) << "the bias term must count somewhere";
    }
    // Measured on llvmpipe 2026-11-26: 7.79e-5 unweighted (E is a mean of |L̃ − L|, differences
    // of nearby values: S's float noise, ~1e-6, grows ~100×), 7.97e-5 weighted by A (2026-11-29:
    // 7.12e-5, 7.24e-5, and 1.31e-4 with the signed bias at weight 3);
    // before the probe pass 0.582. Not run on hardware; the analogous arithmetic differed
    // 60–120× more on an NVIDIA H200 than on llvmpipe (GpuGradientMethod 9.1e-5 vs 1.46e-6,
    // GpuOcclusionWeights 3.3e-5 vs 2.8e-7, issue 23): ×1.5 of the largest case's 1.31e-4 × 120.
    // The truncated loops are 24× above it.
    EXPECT_LT(worst, 2.4e-2);
  }
}

/// spotScene() with its density on the host and the GPU, and the CPU volume tracer with steps of
/// kStep: what the sample-for-sample comparisons below start from.
struct SpotSampling {
  static constexpr float kStep = 1.0f / 24;
  Scene scene = spotScene();
  DensityGrid density{scene.medium.bounds, scene.medium.resolution};
  std::unique_ptr<RadianceEvaluator> cpuEval;
  gpu::Volume gpuDensity;
  SpotSampling() {
    scene.medium.density->build(density);
    PipelineSettings ps;
    ps.delta1 = kStep;
    ps.delta2 = kStep;
    cpuEval = radianceEvaluators().get("volume-tracer", "evaluator").on[int(Backend::Cpu)](ps);
    gpuDensity = gpu::uploadDensity(density);
  }
};

/// The extensions (issue 11): relative ε, 40 probes and a sample budget give the CPU's samples.
TEST(GpuDynamicSampling, RelativeEpsilonProbesAndBudgetAsOnCpu) {
  SCATTERLAB_REQUIRE_GPU();
  const SpotSampling f;
  const Scene& scene = f.scene;
  const DensityGrid& density = f.density;
  const float delta1 = SpotSampling::kStep, delta2 = SpotSampling::kStep;
  RadianceEvaluator* cpuEval = f.cpuEval.get();
  const gpu::Volume& d = f.gpuDensity;
  DynamicSamplingSettings ds;
  ds.levels = {8, 12};
  ds.delta1 = delta1;
  ds.relative = true;
  ds.epsilon = 0.05;
  ds.probes = 40;
  for (long long cap : {0LL, 200LL, 600LL, kAutoBudget, -250LL}) {
    // -250: a budget of 250 on three split levels at ε = 8, where the finest level splits less
    // than its share and the top-up (budgetTopUp) spends the rest on the capped coarser
    // candidates (measured: 9 top-up splits, every capped one, 249 samples; with the sample by
    // sample order before issue 33, 3 and 239).
    const bool topUp = cap == -250;
    ds.levels = topUp ? std::vector<int>{8, 12, 16} : std::vector<int>{8, 12};
    ds.epsilon = topUp ? 8.0 : 0.05;
    ds.maxSamples = topUp ? 250 : cap;
    const DynamicSamplingResult cpu =
        dynamicSampling(scene, density, latticeSamples(), *cpuEval, ds);
    std::vector<std::vector<float>> errors;
    const DynamicSamplingResult g =
        gpu::dynamicSamplingGpu(scene, d, latticeSamples(), {delta1, delta2}, ds, nullptr, &errors);
    expectNoGlError();
    // No E within 1e-3 relative of the threshold of the returned pass (else a flag could flip).
    double closest = 1e30;
    for (const auto& level : errors)
      for (float e : level)
        closest = std::min(closest, std::abs(double(e) / cpu.levels[0].threshold - 1.0));
    std::printf("cap %lld: %zu samples, threshold %.4g (scale %.4g), closest E %.3g\n", cap,
                cpu.samples.size(), cpu.levels[0].threshold, cpu.levels[0].errorScale, closest);
    EXPECT_GT(closest, 1e-3);
    EXPECT_NEAR(g.levels[0].errorScale, cpu.levels[0].errorScale, 1e-4 * cpu.levels[0].errorScale);
    EXPECT_NEAR(g.levels[0].threshold, cpu.levels[0].threshold, 1e-4 * cpu.levels[0].threshold);
    EXPECT_EQ(g.levels[0].budget, cpu.levels[0].budget);
    EXPECT_GT(cpu.levels[0].split, 0);
    long long capped = 0, toppedUp = 0;
    if (ds.maxSamples > 0) {
      // One pass within the budget, split worst first by error groups: budgetedSplit on the
      // CPU, the histograms' cut (dynamic_budget.comp.glsl) on the GPU.
      EXPECT_LE((long long)cpu.samples.size(), ds.maxSamples);
      EXPECT_EQ(cpu.levels[0].budget, ds.maxSamples);
      for (const LevelStats& l : cpu.levels) {
        capped += l.capped;
        toppedUp += l.toppedUp;
      }
      if (topUp) {
        EXPECT_GT(toppedUp, 0);
      } else {
        EXPECT_GT(capped, 0);
      }
    }
    for (std::size_t l = 0; l < cpu.levels.size(); ++l)
      std::printf("  level %zu: evaluated %lld, split %lld (topped up %lld), capped %lld\n", l,
                  cpu.levels[l].samples, cpu.levels[l].split, cpu.levels[l].toppedUp,
                  cpu.levels[l].capped);
    // The same decisions (or, on a device whose E rounds an E at a cut's edge across it, a
    // difference that explains; then the samples are not compared one by one).
    if (!sameDecisions(g, cpu, errors)) continue;
    int bad = 0, badS = 0;
    float sMax = 0.0f;
    for (const RadianceSample& c : cpu.samples)
      sMax = std::max(sMax, std::max(c.S.x, std::max(c.S.y, c.S.z)));
    for (std::size_t i = 0; i < cpu.samples.size(); ++i) {
      bad += g.samples[i].position != cpu.samples[i].position ||
             g.samples[i].level != cpu.samples[i].level;
      // S as SameSampleSetAsCpu checks it (the top-up's children, evaluated in their own GPU
      // pass, are the last samples).
      for (int c = 0; c < 3; ++c)
        badS += std::abs(g.samples[i].S[c] - cpu.samples[i].S[c]) >
                1e-3f * (std::abs(cpu.samples[i].S[c]) + 1e-2f * sMax);
    }
    EXPECT_EQ(bad, 0);
    EXPECT_EQ(badS, 0);
  }
}

/// Issue 24: split "cell", the per-voxel fallback and tau "visible" give the CPU's samples, without
/// a budget (the GPU's split pass in cell mode, its S-only final level) and with one (the GPU's
/// cut of the error groups, the top-up's voxel children evaluated without ∇S).
TEST(GpuDynamicSampling, CellSplitAndFallbackAsOnCpu) {
  SCATTERLAB_REQUIRE_GPU();
  const SpotSampling f;
  const Scene& scene = f.scene;
  const DensityGrid& density = f.density;
  const float delta1 = SpotSampling::kStep, delta2 = SpotSampling::kStep;
  RadianceEvaluator* cpuEval = f.cpuEval.get();
  const gpu::Volume& d = f.gpuDensity;
  DynamicSamplingSettings ds;
  ds.levels = {6, 12};
  ds.delta1 = delta1;
  ds.relative = true;
  ds.epsilon = 0.05;
  ds.probes = 40;
  ds.splitCells = true;
  ds.voxelFallback = true;
  ds.voxelDims = IVec3(24);
  ds.visibleTau = true;  // tau "visible" (the default without paper): six more τ traces
  // The count caps, and a cost budget (issue 35 item 3) where the fallback's voxels weigh 1 and a
  // sample 7 + 40: C = 0.7 × 24³ / 47 = 205 samples, 9 635 units, at most 4 × 205 final samples.
  struct Budget {
    long long cap;
    double share;
  };
  for (const Budget b :
       {Budget{0, 0.0}, Budget{400, 0.0}, Budget{kAutoBudget, 0.0}, Budget{0, 0.7}}) {
    const long long cap = b.cap;
    ds.maxSamples = cap;
    ds.costShare = b.share;
    const DynamicSamplingResult cpu =
        dynamicSampling(scene, density, latticeSamples(), *cpuEval, ds);
    std::vector<std::vector<float>> errors;
    const DynamicSamplingResult g =
        gpu::dynamicSamplingGpu(scene, d, latticeSamples(), {delta1, delta2}, ds, nullptr, &errors);
    expectNoGlError();
    double closest = 1e30;
    for (const auto& level : errors)
      for (float e : level)
        closest = std::min(closest, std::abs(double(e) / cpu.levels[0].threshold - 1.0));
    std::printf("cell split + fallback, cap %lld: %zu samples, closest E %.3g\n", cap,
                cpu.samples.size(), closest);
    EXPECT_GT(closest, 1e-3);
    ASSERT_EQ(g.levels.size(), cpu.levels.size());
    ASSERT_EQ(cpu.levels.size(), 4u);
    EXPECT_TRUE(cpu.levels[3].voxels);
    EXPECT_TRUE(g.levels[3].voxels);
    EXPECT_GT(cpu.levels[2].split, 0) << "the scene must reach the fallback";
    const bool same = sameDecisions(g, cpu, errors);
    if (cap > 0) {
      EXPECT_LE((long long)cpu.samples.size(), cap);
    }
    if (b.share > 0.0) {
      const long long budget = sampleBudget(ds, latticeSamples().size());
      EXPECT_EQ(budget, 205);
      const BudgetLimits limits = budgetLimits(ds, budget);
      EXPECT_EQ(limits.sampleUnit, 47);
      long long units = 0, capped = 0;
      for (const RadianceSample& c : cpu.samples) units += c.level == 3 ? 1 : 47;
      for (const LevelStats& l : cpu.levels) capped += l.capped;
      std::printf("cost budget: %zu samples, %lld units of %lld, %lld capped\n", cpu.samples.size(),
                  units, limits.units, capped);
      EXPECT_GT(capped, 0) << "the cost budget must bind";
      EXPECT_LE(units, std::max(limits.units, 47 * (long long)latticeSamples().size()));
      EXPECT_LE((long long)cpu.samples.size(), std::max<long long>(limits.samples, 64));
      // Paid at their cost, the voxels outnumber what the budget's samples alone could buy.
      EXPECT_GT((long long)cpu.samples.size(), budget);
    }
    if (!same) continue;  // a decision at a cut's edge flipped by rounding (sameDecisions)
    int bad = 0, badS = 0, voxels = 0;
    float sMax = 0.0f;
    for (const RadianceSample& c : cpu.samples)
      sMax = std::max(sMax, std::max(c.S.x, std::max(c.S.y, c.S.z)));
    for (std::size_t i = 0; i < cpu.samples.size(); ++i) {
      const RadianceSample &a = g.samples[i], &b = cpu.samples[i];
      bad += a.position != b.position || a.level != b.level || a.radius != b.radius;
      for (int c = 0; c < 3; ++c)
        badS += std::abs(a.S[c] - b.S[c]) > 1e-3f * (std::abs(b.S[c]) + 1e-2f * sMax);
      if (b.level == 3) {
        ++voxels;
        for (int k = 0; k < 3; ++k) {
          EXPECT_EQ(b.dS[k], Vec3(0.0f));
          EXPECT_EQ(a.dS[k], Vec3(0.0f));
        }
      }
    }
    EXPECT_GT(voxels, 0);
    EXPECT_EQ(bad, 0);
    EXPECT_EQ(badS, 0);
  }
}

TEST(GpuDynamicSampling, InfiniteAndZeroEpsilon) {
  SCATTERLAB_REQUIRE_GPU();
  const Scene scene = spotScene();
  DensityGrid density(scene.medium.bounds, scene.medium.resolution);
  scene.medium.density->build(density);
  const gpu::Volume d = gpu::uploadDensity(density);
  DynamicSamplingSettings ds;
  ds.levels = {8};
  ds.delta1 = 1.0f / 24;
  ds.epsilon = 1e30;
  const auto inf = gpu::dynamicSamplingGpu(scene, d, latticeSamples(), {ds.delta1, ds.delta1}, ds);
  EXPECT_EQ(inf.samples.size(), 64u);
  ds.epsilon = 0.0;  // every sample with E > 0 splits; the 4³ spheres of radius 0.25 cover G1
  const auto zero = gpu::dynamicSamplingGpu(scene, d, latticeSamples(), {ds.delta1, ds.delta1}, ds);
  long long level1 = 0;
  for (const auto& s : zero.samples) level1 += s.level == 1;
  EXPECT_EQ(zero.levels[1].samples, level1);
  EXPECT_GT(level1, 0);
  expectNoGlError();
}

/// A level with more samples than its capacity is cut on the GPU and reported once, after the
/// pass, naming the level, the count it asked for and the capacity.
TEST(GpuDynamicSampling, LevelOverflowIsReportedAfterThePass) {
  SCATTERLAB_REQUIRE_GPU();
  const Scene scene = spotScene();
  DensityGrid density(scene.medium.bounds, scene.medium.resolution);
  scene.medium.density->build(density);
  const gpu::Volume d = gpu::uploadDensity(density);
  DynamicSamplingSettings ds;
  ds.levels = {8};
  ds.delta1 = 1.0f / 24;
  ds.epsilon = 0.0;  // every sample with E > 0 splits
  gpu::DynamicSamplingWorkspace w;
  const auto full = gpu::dynamicSamplingGpu(scene, d, latticeSamples(), {ds.delta1, ds.delta1}, ds,
                                            nullptr, nullptr, nullptr, &w);
  const long long asked = full.levels[1].samples;
  ASSERT_GT(asked, 100);
  w.maxLevelSamples = 100;
  try {
    gpu::dynamicSamplingGpu(scene, d, latticeSamples(), {ds.delta1, ds.delta1}, ds, nullptr,
                            nullptr, nullptr, &w);
    ADD_FAILURE() << "no overflow reported";
  } catch (const GpuError& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find("level 1 (grid 8^3) has " + std::to_string(asked) +
                        " samples, more than "
                        "the 100"),
              std::string::npos)
        << what;
  }
  expectNoGlError();
  // The workspace works again once the capacity suffices.
  w.maxLevelSamples = gpu::kMaxLevelSamples;
  const auto again = gpu::dynamicSamplingGpu(scene, d, latticeSamples(), {ds.delta1, ds.delta1}, ds,
                                             nullptr, nullptr, nullptr, &w);
  EXPECT_EQ(again.samples.size(), full.samples.size());
}

RenderResult renderWith(Scene s, const Json& render, const char* backend) {
  s.render = render;
  return createMethod(s, "", backend)->render(s, nullptr);
}

// Both the extensions (the default: V = S / A interpolated, A multiplied back) and the paper.
class GpuGradientMethod : public ::testing::TestWithParam<bool> {};

TEST_P(GpuGradientMethod, EndToEndMatchesCpuMethod) {
  SCATTERLAB_REQUIRE_GPU();
  const Scene scene = sceneFromJson(blobSceneDoc(20, 32, 24));  // point light inside
  const Json render{{"method", "gradient"},
                    {"paper", GetParam()},
                    {"sampler", {{"type", "jittered"}, {"count", 64}}},
                    {"march_step", 0.5 / 20}};
  const RenderResult cpu = renderWith(scene, render, "cpu");
  const RenderResult gpu = renderWith(scene, render, "gpu");
  expectNoGlError();
  EXPECT_EQ(gpu.stats.backend, "gpu");
  EXPECT_EQ(gpu.stats.method, "gradient");
  EXPECT_EQ(gpu.stats.device, gpu::context().info().renderer);
  EXPECT_EQ(*gpu.stats.samples, *cpu.stats.samples);
  EXPECT_EQ(gpu.stats.extra["uncovered_voxels"], cpu.stats.extra["uncovered_voxels"]);
  const Json j = gpu.stats.toJson();
  for (const char* stage : {"density", "sampling", "evaluation", "reconstruction", "march"})
    EXPECT_TRUE(j["timings_ms"].contains(stage)) << stage;
  EXPECT_TRUE(gpu.stats.extra["gpu_ms"].contains("radiance evaluation"));
  const double err = relL2(gpu.image, cpu.image);
  std::printf("gradient (paper %d) gpu vs cpu: relative L2 %.3g\n", int(GetParam()), err);
  // Measured on llvmpipe 2026-11-26 (compute pipeline): extensions 1.46e-6, paper 1.66e-6; on
  // an NVIDIA H200 (driver 580), 2026-11, issue 23 (raster pipeline, hardware exp/fma in the
  // tracing): 9.1e-5. ×1.5 of the larger.
  EXPECT_LT(err, 1.4e-4);
}
INSTANTIATE_TEST_SUITE_P(ExtensionsAndPaper, GpuGradientMethod, ::testing::Bool());

class GpuAdaptiveMethod : public ::testing::TestWithParam<bool> {};

TEST_P(GpuAdaptiveMethod, EndToEndMatchesCpuMethod) {
  SCATTERLAB_REQUIRE_GPU();
  const Scene scene = spotScene();
  Json render{{"method", "adaptive"},
              {"paper", GetParam()},
              {"sampler", {{"type", "grid"}, {"count", 64}}},
              {"levels", {8, 12}},
              {"epsilon", GetParam() ? 2e-4 : 0.05}};
  if (!GetParam()) render["voxel_switch"] = 0;  // dynamic sampling, not per-voxel instead
  const RenderResult cpu = renderWith(scene, render, "cpu");
  const RenderResult gpu = renderWith(scene, render, "gpu");
  expectNoGlError();
  EXPECT_EQ(gpu.stats.method, "adaptive");
  EXPECT_EQ(gpu.stats.backend, "gpu");
  EXPECT_EQ(*gpu.stats.samples, *cpu.stats.samples);
  EXPECT_EQ(gpu.stats.extra["samples_per_level"], cpu.stats.extra["samples_per_level"]);
  const Json j = gpu.stats.toJson();
  for (const char* stage : {"density", "sampling", "dynamic_sampling", "reconstruction", "march"})
    EXPECT_TRUE(j["timings_ms"].contains(stage)) << stage;
  // Both split and scan on the GPU; the extensions' sample budget (on by default) cuts its error
  // groups there too (issue 33).
  EXPECT_TRUE(gpu.stats.extra["gpu_ms"].contains("ds scan"));
  EXPECT_EQ(gpu.stats.extra["gpu_ms"].contains("ds budget"), !GetParam());
  EXPECT_EQ(gpu.stats.extra.contains("budget"), !GetParam());
  const double err = relL2(gpu.image, cpu.image);
  std::printf("adaptive (paper %d) gpu vs cpu: %lld samples, relative L2 %.3g\n", int(GetParam()),
              *gpu.stats.samples, err);
  // Measured on llvmpipe 2026-11-26 (compute pipeline): extensions 1.45e-6, paper 1.33e-6; on
  // an NVIDIA H200 (driver 580), 2026-11, issue 23 (raster pipeline): extensions 3.3e-5,
  // paper 1.0e-3 (the same sample counts). With a GPU's approximate built-ins simulated
  // (SCATTERLAB_GPU_IMPRECISE=2 / 4, 2026-12-07): extensions 1.0e-4 / 1.04e-4, paper 7.2e-3 /
  // 7.9e-3, the same counts again. That was put down to the paper's tiny epsilon taking other
  // splits; it was the gathers' sphere test (length(d) < R let voxel centres on the level
  // samples' spheres in; d² < R² since 2026-12-08). Re-measured then: llvmpipe 5.9e-7 / 3.7e-7,
  // N = 2: 2.8e-6 / 5.9e-6, N = 4: 6.8e-6 / 1.33e-5. The H200's figures (old test, raster
  // splat) are not re-measured and still set the limits: ×1.5 of the largest, per variant.
  EXPECT_LT(err, GetParam() ? 1.5e-3 : 5.0e-5);
}
INSTANTIATE_TEST_SUITE_P(ExtensionsAndPaper, GpuAdaptiveMethod, ::testing::Bool());

/// A one-dimensional pass past GL's least workgroup count per axis (65 535) spans two axes
/// (gpu/dispatch.h linearDispatch): dynamic sampling's passes over a 256³ level grid's
/// vertices did not, and `adaptive` at 256³ with its defaults was a GpuError on llvmpipe (and
/// on any device whose x-limit is 65 535). Here rows of 3 workgroups make every 1D pass of a
/// small scene fold as a 256³ one does — the scan, the budget's vertex pass, the compaction, the
/// final list's assembly, and the count pass's indirect sizes — and every image, sample count and
/// scan is the unfolded one bit for bit.
TEST(GpuDispatch, OneDimensionalPassesPastTheAxisLimitFoldAndChangeNoBit) {
  SCATTERLAB_REQUIRE_GPU();
  struct Fold {
    Fold(GLuint f) { gpu::setLinearFoldForTesting(f); }
    ~Fold() { gpu::setLinearFoldForTesting(0); }
  };
  EXPECT_EQ(gpu::linearDispatch(65535), UVec3(65535, 1, 1));
  EXPECT_EQ(gpu::linearDispatch(65536), UVec3(65535, 2, 1));
  EXPECT_EQ(gpu::linearDispatch(66306), UVec3(65535, 2, 1));  // 257³ vertices / 256
  std::mt19937 rng(5);
  std::vector<std::uint8_t> flags(100000);
  for (auto& f : flags) f = std::uint8_t(rng() % 3 == 0);
  std::vector<std::uint32_t> cpu(flags.size()), gpu(flags.size());
  const std::uint32_t total = exclusiveScan(flags, cpu);
  const Scene scene = spotScene(24, 18);
  const std::vector<Json> renders = {
      Json{{"method", "adaptive"}, {"voxel_switch", 0}},  // budget, top-up, per-voxel fallback
      Json{{"method", "adaptive"}, {"paper", true}},
      Json{
          {"method", "adaptive"}, {"voxel_switch", 0}, {"tau", "sample"}}};  // level-sized evaluate
  std::vector<RenderResult> plain;
  for (const Json& r : renders) plain.push_back(renderWith(scene, r, "gpu"));
  {
    const Fold fold(3);
    EXPECT_EQ(gpu::linearDispatch(7), UVec3(3, 3, 1));
    EXPECT_EQ(gpu::exclusiveScanGpu(flags, gpu), total);  // 196 blocks: 66 rows of 3
    EXPECT_TRUE(cpu == gpu);
    for (std::size_t i = 0; i < renders.size(); ++i) {
      const RenderResult folded = renderWith(scene, renders[i], "gpu");
      expectNoGlError();
      EXPECT_EQ(folded.stats.samples, plain[i].stats.samples) << renders[i].dump();
      EXPECT_TRUE(folded.image.pixels() == plain[i].image.pixels()) << renders[i].dump();
    }
  }
  EXPECT_EQ(gpu::linearDispatch(7), UVec3(7, 1, 1));
}

/// The default levels (issue 35, forInitialSamples()): one decision for both backends. At 56³
/// the finest allowed, 28, is added after 16; at 64³ with 6000 initial samples (18 per axis)
/// 16 is dropped, no finer than them.
TEST(GpuAdaptiveMethod, DefaultLevelsFollowTheInitialSamplesAsOnCpu) {
  SCATTERLAB_REQUIRE_GPU();
  struct Case {
    int resolution, count;
    std::vector<int> grids;  // the stats' grid per level: 0 for the initial samples, last the
                             // per-voxel fallback's voxels (on by default)
  };
  for (const Case& c : {Case{56, 64, {0, 16, 28, 56}}, Case{64, 6000, {0, 32, 64}}}) {
    Scene scene = spotScene(24, 18);
    scene.medium.resolution = IVec3(c.resolution);
    const Json render{{"method", "adaptive"},
                      {"sampler", {{"type", "grid"}, {"count", c.count}}},
                      {"voxel_switch", 0}};
    const RenderResult cpu = renderWith(scene, render, "cpu");
    const RenderResult gpu = renderWith(scene, render, "gpu");
    expectNoGlError();
    std::vector<int> grids;
    for (const Json& l : cpu.stats.extra["levels"]) grids.push_back(l["grid"].get<int>());
    EXPECT_EQ(grids, c.grids) << c.resolution;
    // The same levels on the GPU; their counts equal unless an E at an edge flipped by rounding
    // (decisionBound).
    EXPECT_EQ(gpu.stats.extra.at("samples_per_level").size(),
              cpu.stats.extra.at("samples_per_level").size());
    const double err = relL2(gpu.image, cpu.image);
    std::printf("%d³, %d initial: %lld samples, gpu vs cpu relative L2 %.3g\n", c.resolution,
                c.count, *gpu.stats.samples, err);
    // Measured on llvmpipe 2026-11-28: 4.1e-7 (56³), 1.5e-6 (64³), the same samples per level;
    // not yet on hardware, so the bound of EndToEndMatchesCpuMethod's extensions, whose H200
    // figure (3.3e-5) it carries, where the decisions agree.
    EXPECT_LT(err, decisionBound(gpu.stats.extra.value("samples_per_level", Json()),
                                 cpu.stats.extra.value("samples_per_level", Json()), 5.0e-5));
  }
}

/// tau "visible" (the default) traces τ at a sample and its six axis probes: the evaluate pass
/// gives each its own invocation (8 lanes per sample, issue 34: seven traces in series made the
/// pass latency-bound), and the images are those of one invocation per sample (checked bit for
/// bit against the previous binary on 12 GPU renders). Level 0's pass is a direct dispatch:
/// its invocations are counted, at least 7 per initial sample; with tau "sample" one each.
TEST(GpuAdaptiveMethod, VisibleTauTracesTheSampleAndItsProbesInParallel) {
  SCATTERLAB_REQUIRE_GPU();
  Scene scene = spotScene(24, 18);
  const Json render{
      {"method", "adaptive"}, {"sampler", {{"type", "grid"}, {"count", 512}}}, {"voxel_switch", 0}};
  Json own = render;
  own["tau"] = "sample";
  const RenderResult cpu = renderWith(scene, render, "cpu");
  const RenderResult visible = renderWith(scene, render, "gpu");
  const RenderResult sample = renderWith(scene, own, "gpu");
  expectNoGlError();
  const long long initial = cpu.stats.extra["samples_per_level"][0].get<long long>();
  const auto evaluate = [](const RenderResult& r) {
    return r.stats.extra.at("invocations").at("ds evaluate").get<long long>();
  };
  EXPECT_GE(evaluate(visible), 7 * initial);
  EXPECT_LT(evaluate(sample), 2 * initial);
  const double err = relL2(visible.image, cpu.image);
  std::printf(
      "tau visible: evaluate %lld invocations (tau sample %lld), %lld initial; gpu vs cpu "
      "%.3g\n",
      evaluate(visible), evaluate(sample), initial, err);
  // Measured on llvmpipe 2026-11-28: 5.6e-7 (4 096 invocations for 494 initial samples; 512
  // with tau "sample"), the CPU's samples per level; 2026-12-07 8.3e-7, with
  // SCATTERLAB_GPU_IMPRECISE=2 / 4 4.8e-5 / 5.2e-5 (the same counts: the gathers' old
  // length(d) < R test); 2026-12-08, with d² < R²: 8.3e-7, N = 2 / 4 / 8 2.95e-6 / 4.89e-6 /
  // 1.42e-5. Since the rays and a sample's light geometry are the CPU's (cpu_arithmetic.glsl,
  // 2026-12-08): 4.4e-7 (478 initial samples), N = 2 / 4 / 8 4.1e-7 / 3.9e-7 / 4.0e-7 — what
  // grew with N was the geometry, not `exp`. Not measured on hardware: the hardware factor on
  // llvmpipe's figure (unmeasuredOnHardware, 1.8e-6).
  EXPECT_LT(err, decisionBound(visible.stats.extra.value("samples_per_level", Json()),
                               cpu.stats.extra.value("samples_per_level", Json()),
                               unmeasuredOnHardware(4.4e-7)));
}

/// The glow scene (a point light inside the medium) at 32³, 80×60: the compute march and the
/// raster slice marcher with ray-step layers are within 0.5% of the CPU's image; view planes
/// are not (0.53%).
TEST(GpuPerVoxelMethod, GlowSceneWithinHalfAPercent) {
  SCATTERLAB_REQUIRE_GPU();
  initialize();
  const Scene scene =
      loadScene(kGlow, {"medium.resolution=32", "camera.width=80", "camera.height=60"});
  const Json render{{"method", "per-voxel"}};
  const RenderResult cpu = renderWith(scene, render, "cpu");
  const RenderResult compute = renderWith(scene, render, "gpu");
  Json raster = render;
  raster["gpu_pipeline"] = "raster";
  const RenderResult gpu = renderWith(scene, raster, "gpu");
  Json planes = raster;
  planes["slicing"] = "view-planes";
  const RenderResult gv = renderWith(scene, planes, "gpu");
  const double err = relL2(gpu.image, cpu.image), errPlanes = relL2(gv.image, cpu.image);
  const double errCompute = relL2(compute.image, cpu.image);
  std::printf("glow per-voxel gpu vs cpu: compute %.3g, ray-steps %.3g, view-planes %.3g\n",
              errCompute, err, errPlanes);
  EXPECT_EQ(gpu.stats.extra["slicing"].get<std::string>(), "ray-steps");
  EXPECT_LT(errCompute, 0.005);
  EXPECT_LT(err, 0.005);
  // Measured 0.00533 (llvmpipe, Mesa 22.3); the bound is that × 1.5, so a regression of the
  // view-plane slicing shows while float noise does not.
  EXPECT_LT(errPlanes, 0.008);
}

}  // namespace
}  // namespace scatterlab::testing

namespace scatterlab::testing {
namespace {

/// `adaptive` with one extension key set to true, from 64 grid samples on the blob scene, on
/// both backends: the same sample count, and the image difference (printed) returned.
double adaptiveExtensionGpuVsCpu(const char* key, const Json& levels) {
  Scene scene = sceneFromJson(blobSceneDoc(20, 32, 24));
  scene.render = {{"method", "adaptive"},
                  {key, true},
                  {"sampler", {{"type", "grid"}, {"count", 64}}},
                  {"levels", levels},
                  {"voxel_switch", 0}};
  const RenderResult cpu = createMethod(scene, "", "cpu")->render(scene, nullptr);
  const RenderResult gpu = createMethod(scene, "", "gpu")->render(scene, nullptr);
  expectNoGlError();
  EXPECT_EQ(*gpu.stats.samples, *cpu.stats.samples);
  const double err = relL2(gpu.image, cpu.image);
  std::printf("adaptive with %s gpu vs cpu: %lld samples, relative L2 %.3g\n", key,
              *gpu.stats.samples, err);
  return err;
}

// Occlusion-aware weights (render.occlusion_weights): the GPU splat marches the density between
// sample and voxel as the CPU gather does.
TEST(GpuOcclusionWeights, AdaptiveMatchesCpu) {
  SCATTERLAB_REQUIRE_GPU();
  // Measured on llvmpipe 2026-11-26 (compute pipeline): 2.82e-7; on an NVIDIA H200 (driver 580),
  // 2026-11, issue 23 (raster pipeline): 3.3e-5. ×1.5 of the larger.
  EXPECT_LT(adaptiveExtensionGpuVsCpu("occlusion_weights", {8}), 5.0e-5);
}

// Log space (render.log_space) with the bounded Taylor terms: the GPU error pass compares
// exp(û) with exp(u) and clamps û to [ln kMinV, 0], the splat clamps before weighting and the
// normalisation exponentiates, as the CPU does.
TEST(GpuLogSpace, AdaptiveMatchesCpu) {
  SCATTERLAB_REQUIRE_GPU();
  // Measured on llvmpipe 2026-11-26 (compute pipeline): 3.41e-7 (446 samples, as many as the
  // CPU's); on an NVIDIA H200 (driver 580), 2026-11, issue 23 (raster pipeline): 5.3e-5. ×1.5 of
  // the larger.
  EXPECT_LT(adaptiveExtensionGpuVsCpu("log_space", {8, 10}), 8.0e-5);
}

// The near-lamp model (render.lamp_model, on by default with factor_lights; the blob scene's
// point light is inside the medium): the GPU's A, V and Eq. 5 evaluate m_l from the density
// texture at the light, the CPU from the density grid.
TEST(GpuLampModel, AdaptiveMatchesCpu) {
  SCATTERLAB_REQUIRE_GPU();
  // Measured on llvmpipe 2026-11-26 (compute pipeline): 3.17e-7 (240 samples, as many as the
  // CPU's). Not measured on hardware; the sibling extensions above, the same gather with one more
  // exp per light and step, differed by up to 5.3e-5 on an NVIDIA H200 (GpuLogSpace, issue 23):
  // ×1.5 of that, as theirs.
  EXPECT_LT(adaptiveExtensionGpuVsCpu("lamp_model", {8}), 8.0e-5);
}

}  // namespace
}  // namespace scatterlab::testing
