/// Dynamic sampling (paper Sec. 5): error metric, splitting, scan compaction.

#include <gtest/gtest.h>

#include <bit>
#include <cstdint>
#include <fstream>
#include <functional>
#include <limits>
#include <random>
#include <sstream>
#include <string>

#include "cpu/interpolation.h"
#include "cpu/radiance_evaluator.h"
#include "sampling/dynamic_sampling.h"
#include "sampling/scan.h"
#include "shading/transport.h"
#include "support/scenes.h"

using namespace scatterlab;
using scatterlab::testing::homogeneousBoxDoc;
using scatterlab::testing::sceneFromJson;

namespace {

/// An evaluator with a given analytic field S(x) and its exact gradient.
class AnalyticEvaluator : public RadianceEvaluator {
 public:
  std::function<Vec3(const Vec3&)> S;
  std::function<void(const Vec3&, Vec3[3])> grad;
  void evaluate(Frame&, const Scene&, std::span<RadianceSample> samples, bool gradients) override {
    for (auto& s : samples) {
      s.S = S(s.position);
      if (gradients) grad(s.position, s.dS);
    }
  }
};

/// The CPU radiance evaluator itself (cpu/radiance_evaluator.h): traced S with Δ1 = one voxel
/// and central-difference ∇S with Δ2 = half a voxel.
class TracingEvaluator : public RadianceEvaluator {
 public:
  void evaluate(Frame& frame, const Scene& scene, std::span<RadianceSample> samples,
                bool gradients) override {
    const float d1 = scene.medium.voxelSize();
    evaluateSamples(scene, frame.hostDensity(), TracerSteps{d1, 0.5f * d1}, samples, gradients);
  }
};

DensityGrid densityOf(const Scene& s) {
  DensityGrid g(s.medium.bounds, s.medium.resolution);
  s.medium.density->build(g);
  return g;
}

RadianceSample sampleAt(const Vec3& p, float r) {
  RadianceSample s;
  s.position = p;
  s.radius = r;
  return s;
}

Scene spotScene() {
  Json doc = homogeneousBoxDoc(1.0f, 1.2f, 0.6f, Vec3(0), 1.0f, 16, 12, 64);
  doc["lights"] = Json::parse(R"([{"type": "spot", "position": [0.5, 1.3, 0.5],
      "direction": [0, -1, 0], "intensity": 10, "inner_deg": 10, "outer_deg": 12}])");
  return sceneFromJson(doc);
}

}  // namespace

TEST(Scan, CompactionEqualsSerialReference) {
  std::mt19937 rng(42);
  for (std::size_t n : {0u, 1u, 7u, 4096u, 100003u}) {
    std::vector<std::uint8_t> flags(n);
    for (auto& f : flags) f = (rng() % 3 == 0) ? 1 : 0;
    std::vector<std::uint32_t> expected, offsets(n), serialOffsets(n);
    std::uint32_t sum = 0;
    for (std::size_t i = 0; i < n; ++i) {
      serialOffsets[i] = sum;
      if (flags[i]) {
        expected.push_back(std::uint32_t(i));
        ++sum;
      }
    }
    EXPECT_EQ(exclusiveScan(flags, offsets), sum);
    EXPECT_EQ(offsets, serialOffsets);
    EXPECT_EQ(compactFlags(flags), expected);
  }
}

TEST(LocalShadingError, ZeroForALinearFieldAndScalesWithRCubed) {
  RadianceSample s = sampleAt(Vec3(0.5f), 0.1f);
  const auto lin = [](const Vec3& p) {
    return Vec3(1.0f) + p.x * Vec3(2, 0, 1) - p.z * Vec3(0, 3, 0);
  };
  s.S = lin(s.position);
  s.dS[0] = Vec3(2, 0, 1);
  s.dS[1] = Vec3(0);
  s.dS[2] = Vec3(0, -3, 0);
  Vec3 p[6], S[6];
  float D[6];
  probePoints(s, p);
  for (int i = 0; i < 6; ++i) {
    S[i] = lin(p[i]);
    D[i] = 1.0f;
  }
  EXPECT_NEAR(localShadingError(s, S, D, 1.0f), 0.0f, 1e-9);
  // A constant offset of 0.3 in every channel at every probe: E = R³·0.3·D·τ.
  for (int i = 0; i < 6; ++i) S[i] += Vec3(0.3f);
  EXPECT_NEAR(localShadingError(s, S, D, 0.5f), 1e-3f * 0.3f * 0.5f, 1e-9);
  s.radius = 0.2f;  // probes move but the field is linear: only R³ changes
  probePoints(s, p);
  for (int i = 0; i < 6; ++i) S[i] = lin(p[i]) + Vec3(0.3f);
  EXPECT_NEAR(localShadingError(s, S, D, 0.5f), 8e-3f * 0.3f * 0.5f, 1e-8);
  // bias_weight k: the same offset at every probe is a bias, E = (1 + k)·Eq. 5's ...
  const DynamicSamplingSettings::ErrorSpace plain{};
  EXPECT_NEAR(localShadingError(s, S, D, 0.5f, 6, plain, nullptr, 3.0f), 4.0f * 8e-3f * 0.3f * 0.5f,
              4e-8);
  // ... and offsets of alternating sign cancel in it: Eq. 5's E.
  for (int i = 0; i < 6; ++i) S[i] = lin(p[i]) + Vec3(i % 2 ? -0.3f : 0.3f);
  EXPECT_NEAR(localShadingError(s, S, D, 0.5f, 6, plain, nullptr, 3.0f), 8e-3f * 0.3f * 0.5f, 1e-8);
}

TEST(DynamicSampling, LinearFieldIsNotSplit) {
  const Scene scene =
      sceneFromJson(homogeneousBoxDoc(1.0f, 1.0f, 1.0f, Vec3(0.5f), 1.0f, 8, 6, 32));
  const DensityGrid density = densityOf(scene);
  AnalyticEvaluator ev;
  ev.S = [](const Vec3& p) { return Vec3(2.0f + p.x + 0.5f * p.y - p.z); };
  ev.grad = [](const Vec3&, Vec3 g[3]) {
    g[0] = Vec3(1.0f);
    g[1] = Vec3(0.5f);
    g[2] = Vec3(-1.0f);
  };
  DynamicSamplingSettings st;
  st.epsilon = 1e-9;  // E is zero up to float rounding
  st.delta1 = scene.medium.voxelSize();
  const std::vector<RadianceSample> init = {sampleAt(Vec3(0.3f), 0.2f),
                                            sampleAt(Vec3(0.6f, 0.5f, 0.4f), 0.25f)};
  const DynamicSamplingResult r = dynamicSampling(scene, density, init, ev, st);
  ASSERT_EQ(r.samples.size(), 2u);
  EXPECT_EQ(r.levels[0].split, 0);
  EXPECT_LT(r.levels[0].maxError, 1e-9f);
}

TEST(DynamicSampling, SampleStraddlingSpotConeEdgeIsSplitAndInsideIsNot) {
  const Scene scene = spotScene();
  const DensityGrid density = densityOf(scene);
  TracingEvaluator ev;
  DynamicSamplingSettings st;
  st.delta1 = scene.medium.voxelSize();
  st.levels = {16};
  // Cone of half-angle ~11° from (0.5, 1.3, 0.5): at y = 0.5 its edge is 0.8·tan(11°) ≈ 0.155
  // off the axis.
  const Vec3 edge(0.5f + 0.155f, 0.5f, 0.5f), inside(0.5f, 0.5f, 0.5f), outside(0.1f, 0.5f, 0.15f);
  const std::vector<RadianceSample> init = {sampleAt(edge, 0.08f), sampleAt(inside, 0.04f),
                                            sampleAt(outside, 0.06f)};
  st.epsilon = std::numeric_limits<double>::infinity();
  DynamicSamplingResult r = dynamicSampling(scene, density, init, ev, st);
  ASSERT_EQ(r.samples.size(), 3u);
  st.epsilon = 0.2 * r.levels[0].maxError;
  r = dynamicSampling(scene, density, init, ev, st);
  EXPECT_EQ(r.levels[0].split, 1);
  long long children = 0;
  for (const auto& s : r.samples) {
    if (s.level == 1) {
      EXPECT_LT(glm::length(s.position - edge), 0.08f);
      EXPECT_FLOAT_EQ(s.radius, 1.0f / 16.0f);
      ++children;
    } else {
      EXPECT_NE(s.position, edge);
    }
  }
  EXPECT_GT(children, 4);
  EXPECT_EQ(r.levels[1].samples, children);
}

TEST(DynamicSampling, EpsilonInfinityKeepsInitialAndZeroGivesFinestGrid) {
  const Scene scene =
      sceneFromJson(homogeneousBoxDoc(1.0f, 1.5f, 0.8f, Vec3(0.45f, 0.55f, 0.5f), 2.0f, 8, 6, 64));
  const DensityGrid density = densityOf(scene);
  TracingEvaluator ev;
  const std::vector<RadianceSample> init = {sampleAt(Vec3(0.5f), 0.2f),
                                            sampleAt(Vec3(0.3f, 0.7f, 0.6f), 0.15f)};
  DynamicSamplingSettings st;
  st.delta1 = scene.medium.voxelSize();
  st.levels = {8, 16, 32};
  st.epsilon = std::numeric_limits<double>::infinity();
  DynamicSamplingResult r = dynamicSampling(scene, density, init, ev, st);
  ASSERT_EQ(r.samples.size(), 2u);
  EXPECT_EQ(r.samples[0].position, init[0].position);
  EXPECT_NE(r.samples[0].S, Vec3(0.0f));  // evaluated

  st.epsilon = 0.0;
  r = dynamicSampling(scene, density, init, ev, st);
  GridInfoBuffer finest(scene.medium.bounds, 32);
  long long insideOriginal = 0;
  for (std::size_t v = 0; v < finest.inSet.size(); ++v) {
    const Vec3 q = finest.vertex(v);
    if (glm::length(q - init[0].position) < init[0].radius ||
        glm::length(q - init[1].position) < init[1].radius) {
      ++insideOriginal;
      bool found = false;
      for (const auto& s : r.samples) found |= (s.level == 3 && s.position == q);
      EXPECT_TRUE(found) << "finest vertex " << v << " missing";
    }
  }
  EXPECT_GT(insideOriginal, 100);
  for (const auto& s : r.samples) EXPECT_EQ(s.level, 3);
}

TEST(DynamicSampling, SplitSpheresCoverTheOriginalsAndResultIsDeterministic) {
  const Scene scene = spotScene();
  const DensityGrid density = densityOf(scene);
  TracingEvaluator ev;
  DynamicSamplingSettings st;
  st.delta1 = scene.medium.voxelSize();
  st.levels = {8, 16, 32};
  std::vector<RadianceSample> init;
  for (float x : {0.2f, 0.5f, 0.8f})
    for (float y : {0.2f, 0.5f, 0.8f})
      for (float z : {0.2f, 0.5f, 0.8f}) init.push_back(sampleAt(Vec3(x, y, z), 0.2f));
  st.epsilon = 1e-6;
  const DynamicSamplingResult a = dynamicSampling(scene, density, init, ev, st);
  const DynamicSamplingResult b = dynamicSampling(scene, density, init, ev, st);
  ASSERT_EQ(a.samples.size(), b.samples.size());
  for (std::size_t i = 0; i < a.samples.size(); ++i) {
    EXPECT_EQ(a.samples[i].position, b.samples[i].position);
    EXPECT_EQ(a.samples[i].radius, b.samples[i].radius);
    EXPECT_EQ(a.samples[i].S, b.samples[i].S);
  }
  EXPECT_GT(a.levels[0].split, 0);
  EXPECT_GT(a.samples.size(), init.size());
  // The paper: "the corresponding set of valid spheres covers the volume of the original
  // spheres". Not exactly: a split keeps the vertices strictly inside the sphere, each with the
  // grid interval as radius, so a point near the sphere's edge can lie a little beyond every
  // child (e.g. (0.001, 0.2, 0.2) of a sphere of radius 0.2 at (0.2, 0.2, 0.2) split on an 8³
  // grid is 0.018 beyond its nearest child). Which points those are moves with the split
  // decisions' rounding: of 3000 random points, none uncovered with GCC 12, 1 with clang 14
  // (ASan build), 0.0047 beyond the nearest sphere. Asserted: at most 3 (0.1 %), none more than
  // 0.0071 (the measured gap × 1.5; the finest grid's interval is 1/32 = 0.031) beyond one.
  std::mt19937 rng(7);
  std::uniform_real_distribution<float> u(-1.0f, 1.0f);
  int checked = 0, uncovered = 0;
  float worstGap = 0.0f;
  while (checked < 3000) {
    const Vec3 d(u(rng), u(rng), u(rng));
    if (glm::length(d) >= 1.0f) continue;
    const RadianceSample& o = init[rng() % init.size()];
    const Vec3 p = o.position + 0.999f * o.radius * d;
    float gap = std::numeric_limits<float>::infinity();
    for (const auto& s : a.samples) gap = std::min(gap, glm::length(p - s.position) - s.radius);
    if (gap >= 0.0f) {
      ++uncovered;
      worstGap = std::max(worstGap, gap);
    }
    ++checked;
  }
  std::printf("uncovered %d of %d, worst %.3g beyond the nearest sphere\n", uncovered, checked,
              double(worstGap));
  EXPECT_LE(uncovered, 3);
  EXPECT_LE(worstGap, 0.0071f);
}

TEST(DynamicSampling, SettingsAreValidated) {
  const Scene scene = spotScene();  // resolution 64: finest level at most 32
  const auto parse = [&](const Json& j) {
    Params p(j, "render");
    return parseDynamicSampling(p, scene);
  };
  EXPECT_EQ(parse(Json::object()).levels, (std::vector<int>{16, 32}));
  EXPECT_THROW(parse({{"levels", {16, 8}}}), ConfigError);
  EXPECT_THROW(parse({{"levels", {16, 64}}}), ConfigError);
  EXPECT_THROW(parse({{"levels", Json::array()}}), ConfigError);
  EXPECT_THROW(parse({{"epsilon", -1}}), ConfigError);
  EXPECT_THROW(parse({{"tau", "viewer"}}), ConfigError);
  try {
    parse({{"levels", {16, 64}}});
    FAIL();
  } catch (const ConfigError& e) {
    EXPECT_NE(std::string(e.what()).find("render.levels"), std::string::npos);
  }
}

TEST(DynamicSampling, DefaultLevelsAreFinerThanTheInitialSamplesAndReachTheFinestAllowed) {
  // Issue 35: a level no finer than the initial samples cannot refine them (a split there marks
  // at most one vertex in the sample's cell), so with the default levels it is dropped; the
  // finest level allowed (half the medium resolution) is added where it is 1.5 × the last.
  const Box unit{Vec3(0.0f), Vec3(1.0f)};
  const auto levelsFor = [&](int finest, float r0, bool autoLevels = true) {
    DynamicSamplingSettings s;
    s.levels.clear();
    for (int l : {16, 32, 64})
      if (l <= finest) s.levels.push_back(l);
    s.autoLevels = autoLevels;
    s.finestLevel = finest;
    std::vector<RadianceSample> initial(3);
    for (auto& x : initial) x.radius = r0;
    return forInitialSamples(s, unit, initial).levels;
  };
  using L = std::vector<int>;
  EXPECT_EQ(levelsFor(64, 1.0f / 12), (L{16, 32, 64}));  // 128³, a dense medium: unchanged
  EXPECT_EQ(levelsFor(64, 1.0f / 40), (L{64}));          // sparse: 16 and 32 are coarser
  EXPECT_EQ(levelsFor(64, 1.0f / 32), (L{64}));          // 32 is as fine: dropped too
  EXPECT_EQ(levelsFor(56, 1.0f / 12), (L{16, 32, 56}));  // 112³: 56 ≥ 1.5 × 32
  EXPECT_EQ(levelsFor(48, 1.0f / 12), (L{16, 32, 48}));  // 96³
  EXPECT_EQ(levelsFor(40, 1.0f / 12), (L{16, 32}));      // 80³: 40 < 48
  EXPECT_EQ(levelsFor(36, 1.0f / 60), (L{}));            // finer than every level allowed
  EXPECT_EQ(levelsFor(64, 1.0f / 20), (L{32, 64}));
  EXPECT_EQ(levelsFor(56, 1.0f / 40, false), (L{16, 32}));  // levels given, or paper: as given
}

TEST(DynamicSampling, ParsedDefaultsPaperAndExtended) {
  const Scene scene = spotScene();
  const auto parse = [&](const Json& j, bool paper) {
    Params p(j, "render");
    return parseDynamicSampling(p, scene, paper);
  };
  const DynamicSamplingSettings paper = parse(Json::object(), true);
  EXPECT_FALSE(paper.relative);
  EXPECT_EQ(paper.epsilon, 1e-4);
  EXPECT_EQ(paper.probes, 6);
  EXPECT_EQ(paper.maxSamples, 0);
  EXPECT_THROW(parse({{"max_samples", 100}}, true), ConfigError);
  const DynamicSamplingSettings ext = parse(Json::object(), false);
  EXPECT_TRUE(ext.relative);
  EXPECT_EQ(ext.epsilon, 0.05);
  EXPECT_EQ(ext.probes, 40);
  EXPECT_EQ(ext.maxSamples, kAutoBudget);
  EXPECT_TRUE(ext.autoLevels);  // resolution 64: [16, 32], the finest allowed 32
  EXPECT_EQ(ext.finestLevel, 32);
  EXPECT_FALSE(paper.autoLevels);
  // The default budget: 4 × the initial count, at most 8000, or C below where larger; none with
  // paper or max_samples 0.
  EXPECT_EQ(sampleBudget(ext, 2000), 8000);
  EXPECT_EQ(sampleBudget(ext, 541), 4183);  // 4 × 541 = 2164 < C = 0.75 · 64³ / 47 = 4183.1
  EXPECT_EQ(sampleBudget(ext, 100000), 8000);
  EXPECT_EQ(sampleBudget(paper, 2000), 0);
  EXPECT_EQ(sampleBudget(parse({{"max_samples", 0}}, false), 2000), 0);
  EXPECT_EQ(sampleBudget(parse({{"max_samples", 123.7}}, false), 2000), 123);
  EXPECT_EQ(parse({{"max_samples", 4000}}, false).maxSamples, 4000);
  // The budget as a cost (issue 35): C = budget × radiance voxels / (7 + probes). Absent
  // max_samples the count rule's min(4 × initial, 8000), raised to C where C is larger; with
  // max_samples given the smaller of the two (budget then 0 unless given); not with paper.
  EXPECT_EQ(ext.costShare, kBudgetCostShare);
  DynamicSamplingSettings cost = parse({{"budget", 0.5}}, false);
  EXPECT_EQ(cost.costShare, 0.5);
  cost.voxelDims = IVec3(128);
  EXPECT_EQ(sampleBudget(cost, 2000), 22310);  // 0.5 · 128³ / (7 + 40) = 22310.1 > 8000
  cost.probes = 14;
  EXPECT_EQ(sampleBudget(cost, 2000), 49932);  // 0.5 · 128³ / 21 = 49932.2
  cost.voxelDims = IVec3(64);
  EXPECT_EQ(sampleBudget(cost, 2000), 8000);  // C = 6241 < the count rule's 8000
  EXPECT_EQ(sampleBudget(cost, 1000), 6241);  // C > the count rule's 4000
  EXPECT_EQ(parse({{"max_samples", 3000}}, false).costShare, 0.0);
  DynamicSamplingSettings both = parse({{"budget", 0.5}, {"max_samples", 3000}}, false);
  both.voxelDims = IVec3(128);
  EXPECT_EQ(sampleBudget(both, 2000), 3000);  // the smaller cap
  both.maxSamples = 0;
  EXPECT_EQ(sampleBudget(both, 2000), 22310);                          // no count cap: the cost's
  EXPECT_EQ(sampleBudget(parse({{"budget", 0}}, false), 2000), 8000);  // the count rule alone
  // Per-voxel's traces where the pipeline counted them (the occupied radiance voxels a light
  // reaches), not the whole grid: a sparse medium's per-voxel is cheaper, and so is the budget.
  DynamicSamplingSettings sparse = parse({{"budget", 0.5}}, false);
  sparse.voxelDims = IVec3(128);
  sparse.perVoxelTraces = 1000000;
  EXPECT_EQ(sampleBudget(sparse, 2000), 10638);  // 0.5 · 10⁶ / 47 = 10638.3, not 22310
  sparse.perVoxelTraces = 300000;
  EXPECT_EQ(sampleBudget(sparse, 2000), 8000);  // C = 3191 < the count rule's 8000
  EXPECT_EQ(sampleBudget(sparse, 500), 3191);   // C > the count rule's 2000
  EXPECT_THROW(parse({{"budget", 0.5}}, true), ConfigError);
  EXPECT_THROW(parse({{"budget", -0.5}}, false), ConfigError);
  EXPECT_THROW(parse({{"max_samples", -1}}, false), ConfigError);
  EXPECT_THROW(parse({{"probes", 32}}, false), ConfigError);
}

TEST(LocalShadingError, InnerProbesSeeAFeatureBetweenTheOuterOnes) {
  // S is zero but in a small ball around x + R/2 along the (1,1,1) diagonal: no probe at R
  // (axes, cube and edge diagonals) comes within 0.2 R of it; the inner diagonal probe sits on it.
  RadianceSample s = sampleAt(Vec3(0.5f), 0.2f);
  const Vec3 feature = s.position + 0.5f * s.radius * glm::normalize(Vec3(1.0f));
  const auto field = [&](const Vec3& p) {
    return glm::length(p - feature) < 0.2f * s.radius ? Vec3(2.0f) : Vec3(0.0f);
  };
  Vec3 p[kMaxProbes], S[kMaxProbes];
  float D[kMaxProbes];
  probePoints(s, p, kMaxProbes);
  for (int i = 0; i < kMaxProbes; ++i) {
    S[i] = field(p[i]);
    D[i] = 1.0f;
  }
  EXPECT_FLOAT_EQ(glm::length(p[32] - s.position), 0.5f * s.radius);  // first inner diagonal
  EXPECT_EQ(localShadingError(s, S, D, 1.0f, 6), 0.0f);
  EXPECT_EQ(localShadingError(s, S, D, 1.0f, 26), 0.0f);
  // One probe of 40 sees |0 − 2| = 2: E = R³ · 2 / 40.
  EXPECT_NEAR(localShadingError(s, S, D, 1.0f, 40), 0.008f * 2.0f / 40.0f, 1e-9);
}

TEST(DynamicSampling, RelativeEpsilonIsScaleFree) {
  // The same spot scene with the light 1000× brighter: absolute E scales by 1000, the relative
  // threshold with it, so the same samples split.
  Json doc = homogeneousBoxDoc(1.0f, 1.2f, 0.6f, Vec3(0), 1.0f, 16, 12, 64);
  const auto run = [&](double intensity, bool relative, double eps) {
    doc["lights"] = Json::parse(R"([{"type": "spot", "position": [0.5, 1.3, 0.5],
        "direction": [0, -1, 0], "inner_deg": 10, "outer_deg": 12}])");
    doc["lights"][0]["intensity"] = intensity;
    const Scene scene = sceneFromJson(doc);
    const DensityGrid density = densityOf(scene);
    TracingEvaluator ev;
    DynamicSamplingSettings st;
    st.delta1 = scene.medium.voxelSize();
    st.levels = {8, 16};
    st.relative = relative;
    st.epsilon = eps;
    std::vector<RadianceSample> init;
    for (float x : {0.2f, 0.5f, 0.8f})
      for (float y : {0.2f, 0.5f, 0.8f})
        for (float z : {0.2f, 0.5f, 0.8f}) init.push_back(sampleAt(Vec3(x, y, z), 0.2f));
    return dynamicSampling(scene, density, init, ev, st);
  };
  const DynamicSamplingResult a = run(10.0, true, 0.05), b = run(10000.0, true, 0.05);
  EXPECT_GT(a.levels[0].split, 0);
  EXPECT_GT(a.levels[1].split, 0);
  ASSERT_EQ(a.samples.size(), b.samples.size());
  for (std::size_t i = 0; i < a.samples.size(); ++i)
    EXPECT_EQ(a.samples[i].position, b.samples[i].position);
  EXPECT_NEAR(b.levels[0].errorScale / a.levels[0].errorScale, 1000.0, 1e-3);
  EXPECT_NEAR(b.levels[0].threshold, 0.05 * b.levels[0].errorScale, 1e-12);
  // An absolute ε does not carry over: the one equal to the relative threshold at intensity 10
  // gives the same samples there and more at 10000 (measured 1478 and 1588: the finest level
  // bounds the growth).
  const DynamicSamplingResult c = run(10.0, false, a.levels[0].threshold),
                              d = run(10000.0, false, a.levels[0].threshold);
  EXPECT_EQ(c.samples.size(), a.samples.size());
  EXPECT_GT(d.samples.size(), c.samples.size() + 50);
  EXPECT_GT(d.levels[1].split, c.levels[1].split);
}

TEST(DynamicSampling, ErrorScaleIsTheMeanContributionOfTheInitialSamples) {
  const Scene scene =
      sceneFromJson(homogeneousBoxDoc(1.0f, 1.0f, 1.0f, Vec3(0.5f), 1.0f, 8, 6, 32));
  const DensityGrid density = densityOf(scene);
  AnalyticEvaluator ev;  // S = (1 + x, 2, 3): mean over RGB 2 + x/3; τ from the uniform box
  ev.S = [](const Vec3& p) { return Vec3(1.0f + p.x, 2.0f, 3.0f); };
  ev.grad = [](const Vec3&, Vec3 g[3]) {
    g[0] = Vec3(1, 0, 0);
    g[1] = g[2] = Vec3(0.0f);
  };
  DynamicSamplingSettings st;
  st.delta1 = scene.medium.voxelSize();
  st.relative = true;
  st.epsilon = 0.5;
  const std::vector<RadianceSample> init = {sampleAt(Vec3(0.25f, 0.5f, 0.5f), 0.2f),
                                            sampleAt(Vec3(0.75f, 0.5f, 0.5f), 0.1f)};
  const DynamicSamplingResult r = dynamicSampling(scene, density, init, ev, st);
  // Expected: mean of R³·(2 + x/3)·D·τ with D = 1 and τ = exp(−σt·ℓ), ℓ the path from x_j to
  // the camera inside the box (traced: compare with the traced τ, not a closed form).
  double expected = 0.0;
  for (const RadianceSample& s : init) {
    const float tau = std::exp(-scene.medium.sigmaT *
                               opticalDepth(density, s.position, scene.camera.position, st.delta1));
    expected += double(s.radius) * s.radius * s.radius * (2.0 + s.position.x / 3.0) * tau;
  }
  expected /= 2.0;
  EXPECT_NEAR(r.levels[0].errorScale, expected, 1e-6 * expected);
  EXPECT_NEAR(r.levels[0].threshold, 0.5 * expected, 1e-6 * expected);
}

namespace {

/// TracingEvaluator that counts its calls (one pass: 2 per split level + 1 for the final one).
class CountingEvaluator : public TracingEvaluator {
 public:
  int calls = 0;
  void evaluate(Frame& frame, const Scene& scene, std::span<RadianceSample> samples,
                bool gradients) override {
    ++calls;
    TracingEvaluator::evaluate(frame, scene, samples, gradients);
  }
};

}  // namespace

TEST(DynamicSampling, SampleBudgetHoldsInOnePass) {
  const Scene scene = spotScene();
  const DensityGrid density = densityOf(scene);
  CountingEvaluator ev;
  DynamicSamplingSettings st;
  st.delta1 = scene.medium.voxelSize();
  st.levels = {8, 16, 32};
  st.relative = true;
  st.epsilon = 0.01;
  st.probes = 40;
  std::vector<RadianceSample> init;
  for (float x : {0.2f, 0.5f, 0.8f})
    for (float y : {0.2f, 0.5f, 0.8f})
      for (float z : {0.2f, 0.5f, 0.8f}) init.push_back(sampleAt(Vec3(x, y, z), 0.2f));
  const int onePass = 2 * int(st.levels.size()) + 1;
  const DynamicSamplingResult free = dynamicSampling(scene, density, init, ev, st);
  EXPECT_EQ(ev.calls, onePass);
  EXPECT_EQ(free.levels[0].budget, 0);
  const long long unbudgeted = (long long)free.samples.size();
  // A budget above the unbudgeted count changes nothing: the same samples in the same order.
  st.maxSamples = unbudgeted;
  ev.calls = 0;
  DynamicSamplingResult r = dynamicSampling(scene, density, init, ev, st);
  EXPECT_EQ(ev.calls, onePass);
  EXPECT_EQ(r.levels[0].budget, unbudgeted);
  ASSERT_EQ(r.samples.size(), free.samples.size());
  for (std::size_t i = 0; i < r.samples.size(); ++i) {
    EXPECT_EQ(r.samples[i].position, free.samples[i].position);
    EXPECT_EQ(r.samples[i].level, free.samples[i].level);
  }
  for (const LevelStats& l : r.levels) EXPECT_EQ(l.capped, 0);
  // A third of it: the set fits, in one pass (the evaluator ran 2 × 3 + 1 times, + 1 for a
  // top-up, not 7–11 passes), with the same threshold, and the budget left candidates unsplit (the
  // error left, max_left / threshold, is above 1).
  st.maxSamples = unbudgeted / 3;
  ev.calls = 0;
  r = dynamicSampling(scene, density, init, ev, st);
  long long toppedUp = 0;
  for (const LevelStats& l : r.levels) toppedUp += l.toppedUp;
  EXPECT_EQ(ev.calls, onePass + (toppedUp > 0 ? 1 : 0));  // + the top-up's children, if any
  EXPECT_EQ(r.levels[0].budgetRuns, 1);
  EXPECT_LE((long long)r.samples.size(), st.maxSamples);
  EXPECT_GT((long long)r.samples.size(), (long long)init.size());
  EXPECT_EQ(r.levels[0].threshold, free.levels[0].threshold);
  long long capped = 0;
  float maxLeft = 0.0f;
  for (const LevelStats& l : r.levels) {
    capped += l.capped;
    maxLeft = std::max(maxLeft, l.maxLeft);
  }
  EXPECT_GT(capped, 0);
  EXPECT_GT(double(maxLeft), r.levels[0].threshold);
  // Every level below the finest still got part of the budget (the equal shares): some samples
  // were split on level 1, not only on level 0.
  EXPECT_GT(r.levels[1].split, 0);
  // Fewer than the initial samples: the set never grows.
  st.maxSamples = 5;
  r = dynamicSampling(scene, density, init, ev, st);
  EXPECT_LE(r.samples.size(), init.size());
}

TEST(DynamicSampling, BudgetSplitsTheLargestErrorFirst) {
  // Three samples far apart on a 10³ grid of the unit box (interval 0.1), each sphere (R = 0.12,
  // centred between vertices) holding the same 8 vertices; E = 2, 5, 3 against a threshold of 1.
  const Box box{Vec3(0.0f), Vec3(1.0f)};
  const std::vector<Vec3> centres = {Vec3(0.2f), Vec3(0.5f), Vec3(0.8f)};
  const std::vector<float> radii(3, 0.12f), errors = {2.0f, 5.0f, 3.0f};
  const std::vector<std::int32_t> anc = {0, 1, 2};
  GridInfoBuffer g(box, 10);
  long long fresh = 0;
  g.forEachInSphere(centres[1], radii[1], [&](std::size_t) { ++fresh; });
  ASSERT_EQ(fresh, 8);
  // Room for exactly one split (count 3 → 3 + fresh − 1): the worst (E = 5) splits, the others
  // are capped.
  // A count cap (max_samples): every sample weighs 1, the units and the samples are one count.
  const auto cap = [](long long b) {
    return BudgetLimits{.units = b, .sampleUnit = 1, .samples = b};
  };
  SplitDecision d = budgetedSplit(box, LevelGrid{IVec3(10)}, centres, radii, anc, errors, 1.0,
                                  {3, 3}, cap(3 + fresh - 1), 1);
  EXPECT_EQ(d.split, (std::vector<std::uint8_t>{0, 1, 0}));
  EXPECT_EQ(d.splits, 1);
  EXPECT_EQ(d.capped, 2);
  EXPECT_EQ(d.count.units, 3 + fresh - 1);
  EXPECT_EQ(d.count.samples, 3 + fresh - 1);
  EXPECT_EQ((long long)d.vertices.size(), fresh);
  for (std::int32_t a : d.ancestors) EXPECT_EQ(a, 1);
  EXPECT_FLOAT_EQ(d.maxLeft, 3.0f);
  // Room for two: E = 5 and 3, not 2.
  d = budgetedSplit(box, LevelGrid{IVec3(10)}, centres, radii, anc, errors, 1.0, {3, 3},
                    cap(3 + 2 * (fresh - 1)), 1);
  EXPECT_EQ(d.split, (std::vector<std::uint8_t>{0, 1, 1}));
  EXPECT_FLOAT_EQ(d.maxLeft, 2.0f);
  // The same budget with two split levels left: this level may use half the headroom: one.
  d = budgetedSplit(box, LevelGrid{IVec3(10)}, centres, radii, anc, errors, 1.0, {3, 3},
                    cap(3 + 2 * (fresh - 1)), 2);
  EXPECT_EQ(d.split, (std::vector<std::uint8_t>{0, 1, 0}));
  // The top-up: that share left the budget of one split unused (no finer level here); after
  // the pass it goes to the next worst capped candidate (E = 3, the second kept sample in the
  // result: index 1), not to E = 2.
  std::vector<BudgetLevel> levels(1);
  levels[0].decision = d;
  levels[0].centres = centres;
  levels[0].radii = radii;
  levels[0].anc = anc;
  levels[0].errors = errors;
  levels[0].grid = LevelGrid{IVec3(10)};
  TopUp t = budgetTopUp(box, levels, d.count, cap(3 + 2 * (fresh - 1)));
  EXPECT_EQ(t.removed, (std::vector<std::size_t>{1}));
  EXPECT_EQ((long long)t.children.size(), fresh);
  for (const RadianceSample& c : t.children) {
    EXPECT_EQ(c.level, 1);
    EXPECT_LT(glm::length(c.position - centres[2]), radii[2]);
  }
  EXPECT_EQ(t.toppedUp, (std::vector<long long>{1}));
  EXPECT_EQ(levels[0].decision.split, (std::vector<std::uint8_t>{0, 1, 1}));
  EXPECT_EQ(levels[0].decision.capped, 1);
  EXPECT_FLOAT_EQ(levels[0].decision.maxLeft, 2.0f);
  // The threshold still rules: E = 2 is not a candidate at a threshold of 2.5.
  d = budgetedSplit(box, LevelGrid{IVec3(10)}, centres, radii, anc, errors, 2.5, {3, 3}, cap(1000),
                    1);
  EXPECT_EQ(d.split, (std::vector<std::uint8_t>{0, 1, 1}));
  EXPECT_EQ(d.capped, 0);
}

TEST(DynamicSampling, TheFallbacksVoxelsArePaidAtTheirCost) {
  // Issue 35 item 3: with the budget a cost, a voxel of the per-voxel fallback weighs 1 unit (one
  // S) and a sample 7 + probes; a split into the fallback keeps its sample and adds its cell's
  // voxels. The same three samples as above (E = 2, 5, 3), the next grid the fallback's voxels.
  const Box box{Vec3(0.0f), Vec3(1.0f)};
  const std::vector<Vec3> centres = {Vec3(0.2f), Vec3(0.5f), Vec3(0.8f)};
  const std::vector<float> radii(3, 0.12f), errors = {2.0f, 5.0f, 3.0f};
  const std::vector<std::int32_t> anc = {0, 1, 2};
  const LevelGrid voxels{IVec3(10), true, true};
  GridInfoBuffer g(box, voxels);
  long long cell = 0;
  g.forEachChild(centres[1], radii[1], [&](std::size_t) { ++cell; });
  ASSERT_GT(cell, 1);
  DynamicSamplingSettings st;
  st.probes = 40;
  st.costShare = 0.75;
  // A budget of 4 samples: 188 units, at most 16 final samples.
  const BudgetLimits b = budgetLimits(st, 4);
  EXPECT_EQ(b.sampleUnit, 47);
  EXPECT_EQ(b.units, 4 * 47);
  EXPECT_EQ(b.samples, kFinalListPerBudget * 4);
  // The three samples use 141 of the 188 units: room for 47 voxels, i.e. every split, where as
  // samples (one unit each: a count cap of 4) the 3 + 2 × cell voxels would not fit.
  const BudgetCount before{3 * 47, 3};
  BudgetLimits roomy = b;
  roomy.samples = 1000;
  SplitDecision d = budgetedSplit(box, voxels, centres, radii, anc, errors, 1.0, before, roomy, 1);
  EXPECT_EQ(d.split, (std::vector<std::uint8_t>{1, 1, 1}));
  EXPECT_EQ(d.count.units, 3 * 47 + 3 * cell);  // the samples stay, the voxels are added
  EXPECT_EQ(d.count.samples, 3 + 3 * cell);
  d = budgetedSplit(box, voxels, centres, radii, anc, errors, 1.0, {3, 3},
                    BudgetLimits{.units = 4, .sampleUnit = 1, .samples = 4}, 1);
  EXPECT_EQ(d.split, (std::vector<std::uint8_t>{0, 0, 0}));
  // The final list's limit in samples binds where the units would not: room for 2 × cell voxels.
  BudgetLimits list = roomy;
  list.samples = 3 + 2 * cell;
  d = budgetedSplit(box, voxels, centres, radii, anc, errors, 1.0, before, list, 1);
  EXPECT_EQ(d.split, (std::vector<std::uint8_t>{0, 1, 1}));  // the worst two: E = 5 and 3
  EXPECT_EQ(d.count.samples, 3 + 2 * cell);
  // A count cap (max_samples, where the cost share is 0): one unit per sample, both limits the cap.
  st.maxSamples = 100;
  st.costShare = 0.0;
  const BudgetLimits count = budgetLimits(st, 100);
  EXPECT_EQ(count.sampleUnit, 1);
  EXPECT_EQ(count.units, 100);
  EXPECT_EQ(count.samples, 100);
  // Both given: the cost counts the units, max_samples stays the most final samples.
  st.costShare = 0.75;
  const BudgetLimits both = budgetLimits(st, 60);
  EXPECT_EQ(both.units, 60 * 47);
  EXPECT_EQ(both.samples, 100);             // not 4 × 60
  EXPECT_EQ(budgetLimits(st, 0).units, 0);  // no budget
  EXPECT_EQ(budgetLimits(st, 0).samples, 0);
}

TEST(DynamicSampling, BudgetStatKeysAreDocumented) {
  // The stats of a budgeted pass: every key (top level and per level) is named, backticked, in
  // docs/dynamic-sampling.md, and error_left is the largest E left unsplit / threshold.
  std::vector<LevelStats> levels(3);
  levels[0].threshold = 2.0;
  levels[0].budget = 100;
  levels[0].maxLeft = 3.0f;
  levels[1].maxLeft = 5.0f;
  levels[1].capped = 7;
  levels[2].capped = 1;
  DynamicSamplingSettings st;
  st.relative = true;
  st.maxSamples = kAutoBudget;
  st.costShare = 0.75;
  st.perVoxelTraces = 5000;
  RenderStats rs;
  addDynamicSamplingStats(rs, {.levels = levels}, st);
  EXPECT_EQ(rs.extra["budget"], 100);
  EXPECT_EQ(rs.extra["budget_share"], 0.75);
  EXPECT_EQ(rs.extra["budget_voxels"], 5000);
  EXPECT_EQ(rs.extra["capped"], 8);
  EXPECT_DOUBLE_EQ(rs.extra["error_left"].get<double>(), 2.5);
  EXPECT_EQ(rs.extra["budget_runs"], 1);
  EXPECT_EQ(rs.extra["max_samples"], "auto");
  std::ifstream f(std::string(SCATTERLAB_SOURCE_DIR) + "/docs/dynamic-sampling.md");
  std::stringstream doc;
  doc << f.rdbuf();
  std::vector<std::string> keys;
  for (const auto& [k, v] : rs.extra.items()) keys.push_back(k);
  for (const auto& [k, v] : rs.extra["levels"][0].items()) keys.push_back(k);
  for (const std::string& k : keys)
    EXPECT_NE(doc.str().find("`" + k + "`"), std::string::npos)
        << "stat " << k << " is not in docs/dynamic-sampling.md";
}

namespace scatterlab {
namespace {

TEST(DynamicSampling, ErrorSpaceClampsAndComparesOnV) {
  // A sample holding u = ln V = ln 0.5 with ∇u = (−10, 0, 0), R = 0.1: at the +X probe the
  // Taylor estimate is ln 0.5 − 1, at −X ln 0.5 + 1 (> 0: V = 1.36 > 1, out of range).
  RadianceSample s;
  s.position = Vec3(0.5f);
  s.radius = 0.1f;
  s.S = Vec3(std::log(0.5f));
  s.dS[0] = Vec3(-10.0f);
  Vec3 p[6], S[6];
  float D[6];
  probePoints(s, p);
  for (int i = 0; i < 6; ++i) {
    S[i] = Vec3(std::log(0.5f));  // the truth: V = 0.5 at every probe
    D[i] = 1.0f;
  }
  const float r3 = 1e-3f;
  // Paper (on u itself): |Δu| = 1 at ±X, 0 elsewhere.
  EXPECT_NEAR(localShadingError(s, S, D, 1.0f), r3 * 2.0f / 6.0f, 1e-8);
  DynamicSamplingSettings::ErrorSpace space;
  space.log = true;  // on V: |0.5·e^{-1} − 0.5| + |0.5·e − 0.5|
  const float onV = 0.5f * (1.0f - std::exp(-1.0f)) + 0.5f * (std::exp(1.0f) - 1.0f);
  EXPECT_NEAR(localShadingError(s, S, D, 1.0f, 6, space), r3 * onV / 6.0f, 1e-8);
  space.bounds = TaylorBounds{std::log(kMinV), 0.0f};  // −X clamped to u = 0: V = 1
  const float bounded = 0.5f * (1.0f - std::exp(-1.0f)) + 0.5f;
  EXPECT_NEAR(localShadingError(s, S, D, 1.0f, 6, space), r3 * bounded / 6.0f, 1e-8);
  // The contribution is measured on V too: R³·V·D·τ.
  EXPECT_NEAR(sampleContribution(s, 1.0f, 1.0f, space), r3 * 0.5f, 1e-8);
  EXPECT_NEAR(sampleContribution(s, 1.0f, 1.0f), r3 * std::log(2.0f), 1e-8);
}

TEST(DynamicSampling, ErrorWeightedByAIsTheErrorOfS) {
  // One point light of intensity (1, 2, 3) at l, isotropic phase: A(p) = I / (4π·|p − l|²) per
  // channel, computed here without LightFactor. A sample at x with V = 0.5 and ∇V = 0 (its
  // Taylor estimate is 0.5 everywhere) and the traced V = 0.5 + δ_i at probe i: the weighted E
  // is R³ · Σ_i mean_RGB(δ_i·A_i)·D_i / n · τ, the unweighted R³ · Σ_i δ_i·D_i / n · τ.
  Json doc = homogeneousBoxDoc(1.0f, 1.0f, 1.0f, Vec3(0.5f, 0.75f, 0.5f), 1.0f, 8, 6, 32);
  doc["lights"][0]["intensity"] = {1.0, 2.0, 3.0};
  const Scene scene = sceneFromJson(doc);
  const Vec3 light(0.5f, 0.75f, 0.5f), eye = scene.camera.position;
  const LightFactor A(scene);
  RadianceSample s;
  s.position = Vec3(0.5f, 0.5f, 0.45f);
  s.radius = 0.1f;
  s.S = Vec3(0.5f);
  Vec3 p[kMaxProbes], S[kMaxProbes], probeA[kMaxProbes];
  float D[kMaxProbes];
  probePoints(s, p, kMaxProbes);
  double weighted = 0.0, plain = 0.0;
  for (int i = 0; i < kMaxProbes; ++i) {
    const float delta = 0.01f * float(i + 1);
    S[i] = Vec3(0.5f + delta);
    D[i] = 0.5f + 0.01f * float(i);
    probeA[i] = lightFactorTowardsEye(A, p[i], eye);
    const Vec3 d = p[i] - light;
    const double a = 1.0 / (4.0 * 3.14159265358979 * double(glm::dot(d, d)));  // × I per channel
    const double diff = double((0.5f + delta) - 0.5f);  // |Ṽ − V| in float, as E computes it
    weighted += diff * a * (1.0 + 2.0 + 3.0) / 3.0 * double(D[i]);
    plain += diff * double(D[i]);
  }
  const double r3 = 1e-3, tau = 0.7, n = kMaxProbes;
  const float E = localShadingError(s, S, D, 0.7f, kMaxProbes, {}, probeA);
  EXPECT_NEAR(E, r3 * weighted / n * tau, 1e-6 * r3 * weighted / n * tau);  // float sums
  EXPECT_NEAR(localShadingError(s, S, D, 0.7f, kMaxProbes), r3 * plain / n * tau,
              1e-6 * r3 * plain / n * tau);
  // A is 1/d²: the +Y probe (d² = 0.15² + 0.05²) weighs 5× the −Y probe (d² = 0.35² + 0.05²).
  EXPECT_NEAR(probeA[2].x / probeA[3].x, 0.125f / 0.025f, 1e-4);
  // In log space the difference is taken after exp: the same E for ln V.
  DynamicSamplingSettings::ErrorSpace logSpace;
  logSpace.log = true;
  RadianceSample u = s;
  u.S = Vec3(std::log(0.5f));
  Vec3 lnS[kMaxProbes];
  for (int i = 0; i < kMaxProbes; ++i) lnS[i] = glm::log(S[i]);
  EXPECT_NEAR(localShadingError(u, lnS, D, 0.7f, kMaxProbes, logSpace, probeA), E, 1e-5 * E);
  // The contribution: R³·mean_RGB(A ⊙ V)·D·τ, A at the sample.
  const Vec3 d = s.position - light;
  const float a0 = 1.0f / (4.0f * kPi * glm::dot(d, d));
  const Vec3 As = lightFactorTowardsEye(A, s.position, eye);
  EXPECT_NEAR(sampleContribution(s, 0.8f, 0.7f, {}, &As), 1e-3f * 0.5f * a0 * 2.0f * 0.8f * 0.7f,
              1e-6 * a0 * 1e-3f);
  EXPECT_NEAR(sampleContribution(u, 0.8f, 0.7f, logSpace, &As),
              sampleContribution(s, 0.8f, 0.7f, {}, &As), 1e-6 * a0 * 1e-3f);
}

TEST(DynamicSampling, ErrorWeightedByAIsZeroOutsideTheSpotCone) {
  // V with curvature everywhere (its Taylor estimate misses at every probe) under a narrow spot
  // light (cone of radius ~0.2 at y = 0.5, around x = z = 0.5): weighted by A, only samples
  // whose probes reach into the cone have an error, so only they split; unweighted, every
  // sample has the same error and all split. Weighted, a probe outside the cone adds 0 whatever
  // it would trace, so it is not traced (the population's fog shafts spent most of their first
  // level on such probes): the evaluator's calls without gradients, the probe batches, hold
  // exactly the probe points inside the cone with D > 0.
  const Scene scene = spotScene();
  const DensityGrid density = densityOf(scene);
  struct Recording : AnalyticEvaluator {
    std::vector<Vec3> probed;
    void evaluate(Frame& f, const Scene& sc, std::span<RadianceSample> samples,
                  bool gradients) override {
      if (!gradients)
        for (const auto& s : samples) probed.push_back(s.position);
      AnalyticEvaluator::evaluate(f, sc, samples, gradients);
    }
  } ev;
  ev.S = [](const Vec3& p) { return Vec3(0.2f + glm::dot(p, p)); };
  ev.grad = [](const Vec3& p, Vec3 g[3]) {
    for (int a = 0; a < 3; ++a) g[a] = Vec3(2.0f * p[a]);
  };
  DynamicSamplingSettings st;
  st.levels = {16};
  st.probes = 40;
  st.epsilon = 1e-12;  // every nonzero error splits
  st.delta1 = scene.medium.voxelSize();
  std::vector<RadianceSample> init;
  for (int i = 0; i < 8; ++i)
    for (int k = 0; k < 8; ++k)
      init.push_back(sampleAt(Vec3((i + 0.5f) / 8, 0.5f, (k + 0.5f) / 8), 0.125f));
  const DynamicSamplingResult plain = dynamicSampling(scene, density, init, ev, st);
  EXPECT_EQ(plain.levels[0].split, 64);
  const std::size_t everyProbe = ev.probed.size();
  st.space.weightA = true;
  ev.probed.clear();
  const DynamicSamplingResult weighted = dynamicSampling(scene, density, init, ev, st);
  // The light at (0.5, 1.3, 0.5), outer half-angle 12°: radius 0.8·tan 12° = 0.17 at y = 0.5
  // (more above it); a sample splits iff a probe (at most R = 0.125 away) is inside the cone.
  int expected = 0;
  std::size_t probesInside = 0;
  for (const RadianceSample& s : init) {
    Vec3 p[kMaxProbes];
    probePoints(s, p, kMaxProbes);
    bool inside = false;
    for (int i = 0; i < kMaxProbes; ++i) {
      const Vec3 d = glm::normalize(p[i] - Vec3(0.5f, 1.3f, 0.5f));
      const bool in = -d.y > std::cos(glm::radians(12.0f));
      inside = inside || in;
      probesInside += in && density.sample(p[i]) != 0.0f;
    }
    expected += inside;
  }
  EXPECT_GT(expected, 0);
  EXPECT_LT(expected, 64);
  EXPECT_EQ(weighted.levels[0].split, expected);
  EXPECT_EQ(ev.probed.size(), probesInside);
  EXPECT_LT(probesInside * 4, everyProbe);  // unweighted, every probe with D > 0 was traced
}

}  // namespace
}  // namespace scatterlab

// ---- Issue 24: split "cell" and the per-voxel fallback -------------------------------------

TEST(DynamicSampling, CellSplitMarksTheCellAndTheCellsTileTheNextGrid) {
  const Box box{Vec3(0.0f), Vec3(1.0f)};
  const GridInfoBuffer g8(box, 8);
  const GridInfoBuffer cells(box, LevelGrid{IVec3(16), false, true});
  const GridInfoBuffer spheres(box, LevelGrid{IVec3(16), false, false});
  std::vector<int> hits(cells.vertexCount(), 0);
  for (std::size_t v = 0; v < g8.vertexCount(); ++v) {
    int n = 0;
    cells.forEachChild(g8.vertex(v), g8.radius(), [&](std::size_t c) {
      ++hits[c];
      ++n;
    });
    EXPECT_EQ(n, 8) << "G8 vertex " << v;  // the 2×2×2 vertices of G16 in its cell
  }
  for (std::size_t c = 0; c < hits.size(); ++c) EXPECT_EQ(hits[c], 1) << "G16 vertex " << c;
  // The paper's split of an inner vertex marks the 32 vertices of G16 inside its sphere.
  int n = 0;
  spheres.forEachChild(g8.vertex((3 * 8 + 3) * 8 + 3), g8.radius(), [&](std::size_t) { ++n; });
  EXPECT_EQ(n, 32);
}

TEST(DynamicSampling, FallbackGridIsTheRadianceVoxelsPerAxis) {
  // A non-cubic medium like lamps32.json (128 × 52 × 104 voxels): the fallback's vertices are
  // the radiance volume's voxel centres, bit for bit, and a sample reaches only its own voxel.
  const Box box{Vec3(0.0f), Vec3(2.0f, 0.8f, 1.6f)};
  const IVec3 dims(20, 8, 16);
  const GridInfoBuffer g(box, LevelGrid{dims, true, true});
  const RadianceGrid rg(box, dims);
  ASSERT_EQ(g.vertexCount(), std::size_t(20 * 8 * 16));
  for (int k = 0; k < dims.z; ++k)
    for (int j = 0; j < dims.y; ++j)
      for (int i = 0; i < dims.x; ++i)
        EXPECT_EQ(g.vertex((std::size_t(k) * dims.y + j) * dims.x + i), rg.cellCenter(i, j, k));
  EXPECT_FLOAT_EQ(g.radius(), 0.05f);  // ½ the smallest voxel edge (0.1)
  EXPECT_LT(g.radius(), rg.cellSize().x);
}

TEST(DynamicSampling, OneLevelLoopCallsTheStepsInOrder) {
  // runSplitPass is the level loop of the CPU and the GPU alike: what it calls, in order, for a
  // budgeted pass with the per-voxel fallback, the paper's unbudgeted pass, and no split level.
  struct Recorder final : SplitPassSteps {
    std::string calls;
    void evaluate(std::size_t k, LevelEvaluation e) override {
      calls += "e" + std::to_string(k) + "SFV"[int(e)] + ' ';
    }
    void threshold() override { calls += "t "; }
    void split(std::size_t k) override { calls += "s" + std::to_string(k) + ' '; }
    void endLevel(std::size_t k) override { calls += "|" + std::to_string(k) + ' '; }
    void topUp() override { calls += "top "; }
    void finish() override { calls += "end"; }
  };
  const auto run = [](const SplitPassPlan& plan) {
    Recorder r;
    EXPECT_EQ(runSplitPass(r, plan).size(), plan.levels() + 1);
    return r.calls;
  };
  SplitPassPlan budgeted;
  budgeted.grids = {{IVec3(16), false, true}, {IVec3(32), false, true}, {IVec3(40), true, true}};
  budgeted.budget = 8000;
  EXPECT_TRUE(budgeted.fallback());
  EXPECT_EQ(run(budgeted), "e0S t s0 |0 e1S s1 |1 e2S s2 |2 e3V |3 top end");
  SplitPassPlan paper;
  paper.grids = {{IVec3(16), false, false}, {IVec3(32), false, false}};
  EXPECT_FALSE(paper.fallback());
  EXPECT_EQ(run(paper), "e0S t s0 |0 e1S s1 |1 e2F |2 end");
  SplitPassPlan none;
  none.budget = 8000;
  EXPECT_EQ(run(none), "e0F |0 end");
  // The plan from the settings: the grids of levelGrids(), sampleBudget(), budgetLimits().
  Params p(Json::object(), "render");
  const DynamicSamplingSettings ext = parseDynamicSampling(p, spotScene(), false);
  const SplitPassPlan plan = splitPassPlan(ext, 2000);
  EXPECT_EQ(plan.levels(), levelGrids(ext).size());
  EXPECT_EQ(plan.budget, sampleBudget(ext, 2000));
  EXPECT_EQ(plan.limits.units, budgetLimits(ext, plan.budget).units);
  EXPECT_EQ(plan.limits.samples, budgetLimits(ext, plan.budget).samples);
}

TEST(DynamicSampling, FallbackVoxelsReconstructToTheirOwnS) {
  // A spot shaft in a 16³ medium, one split level (4³) and the fallback: every cell whose E is
  // above 0 gets its voxels evaluated. Where a voxel has its own sample, Eq. 4 gives exactly
  // that sample's S (its weight R/‖x − x_j‖ is clamped at R/1e-9), which is the traced S at the
  // voxel centre: per-voxel accuracy there. The split samples stay (their cells' other voxels
  // would otherwise lose them).
  Json doc = homogeneousBoxDoc(1.0f, 1.2f, 0.6f, Vec3(0), 1.0f, 16, 12, 16);
  doc["lights"] = Json::parse(R"([{"type": "spot", "position": [0.5, 1.3, 0.5],
      "direction": [0, -1, 0], "intensity": 10, "inner_deg": 10, "outer_deg": 12}])");
  const Scene scene = sceneFromJson(doc);
  const DensityGrid density = densityOf(scene);
  TracingEvaluator ev;
  DynamicSamplingSettings st;
  st.delta1 = scene.medium.voxelSize();
  st.levels = {4};
  st.splitCells = true;
  st.voxelFallback = true;
  st.voxelDims = scene.medium.resolution;
  st.epsilon = 1e-9;
  st.probes = 40;  // the inner probes see the shaft between the initial samples
  std::vector<RadianceSample> init;
  for (int k = 0; k < 2; ++k)
    for (int j = 0; j < 2; ++j)
      for (int i = 0; i < 2; ++i) init.push_back(sampleAt((Vec3(i, j, k) + 0.5f) * 0.5f, 0.5f));
  const DynamicSamplingResult r = dynamicSampling(scene, density, init, ev, st);
  ASSERT_EQ(r.levels.size(), 3u);
  EXPECT_TRUE(r.levels[2].voxels);
  EXPECT_GT(r.levels[1].split, 0);
  long long voxelSamples = 0, keptSplit = 0;
  for (const RadianceSample& s : r.samples) {
    voxelSamples += s.level == 2;
    keptSplit += s.level == 1;
    if (s.level != 2) continue;
    EXPECT_FLOAT_EQ(s.radius, 0.5f / 16.0f);
    for (int a = 0; a < 3; ++a) EXPECT_EQ(s.dS[a], Vec3(0.0f));  // no ∇S evaluated
  }
  EXPECT_EQ(voxelSamples, r.levels[2].samples);
  EXPECT_EQ(voxelSamples, 64 * r.levels[1].split);  // 4×4×4 voxels of 16³ per cell of G4
  EXPECT_EQ(keptSplit, r.levels[1].samples);        // the split samples stay
  RadianceGrid out(scene.medium.bounds, scene.medium.resolution);
  interpolateSamples(Interpolation::Gradient, density, r.samples, out);
  int checked = 0;
  for (const RadianceSample& s : r.samples) {
    if (s.level != 2) continue;
    const IVec3 v = IVec3((s.position - scene.medium.bounds.min) / out.cellSize());
    const Vec3 got = out.at(v.x, v.y, v.z);
    for (int c = 0; c < 3; ++c) EXPECT_NEAR(got[c], s.S[c], 1e-5f * (1.0f + s.S[c]));
    ++checked;
  }
  EXPECT_GT(checked, 64);
}

TEST(DynamicSampling, CellSplitAndFallbackKeysParsed) {
  const Scene scene = spotScene();  // 64³
  const auto parse = [&](const Json& j, bool paper) {
    Params p(j, "render");
    return parseDynamicSampling(p, scene, paper);
  };
  const DynamicSamplingSettings paper = parse(Json::object(), true);
  EXPECT_FALSE(paper.splitCells);
  EXPECT_FALSE(paper.voxelFallback);
  EXPECT_TRUE(levelGrids(paper).size() == paper.levels.size());
  EXPECT_THROW(parse({{"split", "cell"}}, true), ConfigError);
  EXPECT_THROW(parse({{"fallback", true}}, true), ConfigError);
  EXPECT_FALSE(paper.visibleTau);
  EXPECT_THROW(parse({{"tau", "visible"}}, true), ConfigError);
  const DynamicSamplingSettings ext = parse(Json::object(), false);
  EXPECT_TRUE(ext.visibleTau);
  EXPECT_FALSE(parse({{"tau", "ancestor"}}, false).visibleTau);
  EXPECT_TRUE(ext.splitCells);
  EXPECT_TRUE(ext.voxelFallback);  // on by default since issue 35, the finest level at 6 probes
  EXPECT_EQ(ext.fallbackProbes, 6);
  EXPECT_EQ(levelProbes(ext, {IVec3(32), false, true}), 40);
  EXPECT_EQ(levelProbes(ext, {IVec3(64), true, true}), 6);
  EXPECT_EQ(parse({{"fallback_probes", 14}}, false).fallbackProbes, 14);
  EXPECT_THROW(parse({{"fallback_probes", 7}}, false), ConfigError);
  EXPECT_THROW(parse({{"fallback_probes", 6}}, true), ConfigError);
  EXPECT_FALSE(parse({{"fallback", false}}, false).voxelFallback);
  EXPECT_FALSE(parse({{"split", "sphere"}}, false).splitCells);
  EXPECT_THROW(parse({{"split", "box"}}, false), ConfigError);
  EXPECT_THROW(parse({{"fallback", 3}}, false), ConfigError);
  const DynamicSamplingSettings fb = parse({{"fallback", true}}, false);
  EXPECT_TRUE(fb.voxelFallback);
  EXPECT_EQ(fb.voxelDims, IVec3(64));
  const std::vector<LevelGrid> grids = levelGrids(fb);
  ASSERT_EQ(grids.size(), fb.levels.size() + 1);
  EXPECT_TRUE(grids.back().voxels);
  EXPECT_EQ(grids.back().dims, IVec3(64));
  EXPECT_TRUE(grids.front().cells);
  // The fallback's voxels follow the pipeline's radiance volume.
  PipelineSettings ps;
  ps.radianceResolution = IVec3(32, 16, 8);
  EXPECT_EQ(withPipeline(fb, ps).voxelDims, IVec3(32, 16, 8));
}

TEST(DynamicSampling, ErrorWeightKeyParsed) {
  const Scene scene = spotScene();
  const auto parse = [&](const Json& j, bool paper, bool factorLights) {
    Params p(j, "render");
    return parseDynamicSampling(p, scene, paper, factorLights);
  };
  // "radiance" (default): with factor_lights E weighs V's error by A; without, S is held.
  EXPECT_TRUE(parse(Json::object(), false, true).space.weightA);
  EXPECT_FALSE(parse(Json::object(), false, false).space.weightA);
  EXPECT_FALSE(parse(Json::object(), true, false).space.weightA);  // the paper's Eq. 5 on S
  EXPECT_FALSE(parse({{"error_weight", "transmittance"}}, false, true).space.weightA);
  EXPECT_THROW(parse({{"error_weight", "transmittance"}}, false, false), ConfigError);
  EXPECT_THROW(parse({{"error_weight", "light"}}, false, true), ConfigError);
  // With directional lights only A varies by the phase alone: unweighted by default.
  Scene sun = scene;
  sun.lights[0].type = Light::Type::Directional;
  Params ps0(Json::object(), "render");
  EXPECT_FALSE(parseDynamicSampling(ps0, sun, false, true).space.weightA);
  Params ps1(Json{{"error_weight", "radiance"}}, "render");
  EXPECT_TRUE(parseDynamicSampling(ps1, sun, false, true).space.weightA);
  // The pipeline keeps it with factor_lights and gives it the lamp model of the samples' A.
  PipelineSettings ps;
  ps.factorLights = true;
  ps.lampModel = true;
  const DynamicSamplingSettings w = withPipeline(parse(Json::object(), false, true), ps);
  EXPECT_TRUE(w.space.weightA);
  EXPECT_TRUE(w.space.lampModel);
  ps.factorLights = false;
  ps.lampModel = false;
  EXPECT_FALSE(withPipeline(parse(Json::object(), false, true), ps).space.weightA);
}

TEST(DynamicSampling, DefaultProbesBoundTheLightTracesPerSample) {
  // 40 probes while probes × lights <= 160, then 26, never fewer than 14 (docs/fidelity.md §13);
  // the paper's 6 and an explicit count whatever the lights.
  const auto probes = [](std::size_t lights, const Json& j, bool paper) {
    Scene scene = spotScene();
    scene.lights.assign(lights, scene.lights[0]);
    Params p(j, "render");
    return parseDynamicSampling(p, scene, paper, !paper).probes;
  };
  EXPECT_EQ(probes(1, Json::object(), false), 40);
  EXPECT_EQ(probes(4, Json::object(), false), 40);
  EXPECT_EQ(probes(5, Json::object(), false), 26);
  EXPECT_EQ(probes(6, Json::object(), false), 26);
  EXPECT_EQ(probes(7, Json::object(), false), 14);
  EXPECT_EQ(probes(32, Json::object(), false), 14);
  EXPECT_EQ(probes(32, Json::object(), true), 6);
  EXPECT_EQ(probes(32, Json{{"probes", 40}}, false), 40);
}

TEST(DynamicSampling, MostVisibleTauIsTheWholeMarchesMaximumBitForBit) {
  // A dense perforated sheet in thin fog (the population's sheet_3: optical depth 3–12 across
  // the sheet), points all over its box: marches from behind the sheet stop once they pass the
  // depth of a point in front, those that finish must sum exactly as opticalDepth does.
  std::ifstream in(SCATTERLAB_SOURCE_DIR "/data/scenes/population/sheet_3.json");
  const Scene scene = sceneFromJson(Json::parse(in));
  const DensityGrid density = densityOf(scene);
  const Box& box = scene.medium.bounds;
  const float delta1 = scene.medium.voxelSize();
  std::mt19937 rng(11);
  std::uniform_real_distribution<float> u(0.0f, 1.0f);
  const auto whole = [&](const Vec3& p) {
    return std::exp(-scene.medium.sigmaT * opticalDepth(density, p, scene.camera.position, delta1));
  };
  int raisedByAPoint = 0;
  for (int trial = 0; trial < 600; ++trial) {
    // The sample and its six axis probes at a radius of 1–8 voxels, as tau "visible" has them.
    const Vec3 c = box.min + box.extent() * Vec3(u(rng), u(rng), u(rng));
    RadianceSample s;
    s.position = c;
    s.radius = delta1 * (1.0f + 7.0f * u(rng));
    Vec3 p[6];
    probePoints(s, p, 6);
    // tau from the sample itself, or an ancestor's (any value in [0, 1], 0 and 1 included).
    const float tau0 = trial % 4 == 0 ? whole(c) : trial % 4 == 1 ? u(rng) : float(trial % 4 - 2);
    float expected = tau0;
    for (const Vec3& q : p) expected = std::max(expected, whole(q));
    const float got = mostVisibleTau(scene, density, tau0, p, 6, delta1);
    EXPECT_EQ(std::bit_cast<std::uint32_t>(got), std::bit_cast<std::uint32_t>(expected))
        << "trial " << trial << ": " << got << " against " << expected;
    raisedByAPoint += expected > tau0;
  }
  EXPECT_GT(raisedByAPoint, 100);  // the probes decide the result often, not only tau0
}
