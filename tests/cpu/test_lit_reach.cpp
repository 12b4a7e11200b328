// Where no spot cone reaches (LitReach, shading/transport.h): with the factored volume the march
// multiplies V by A, so samples and voxels whose reach no cone meets are neither traced nor
// gathered. The test is conservative, and the images are those of every sample traced.

#include <gtest/gtest.h>

#include <random>

#include "core/metrics.h"
#include "cpu/radiance_evaluator.h"
#include "shading/transport.h"
#include "support/scenes.h"

namespace scatterlab {
namespace {

Light spot(Vec3 apex, Vec3 axis, float outerDeg) {
  Light l;
  l.type = Light::Type::Spot;
  l.position = apex;
  l.direction = glm::normalize(axis);
  l.cosOuter = std::cos(glm::radians(outerDeg));
  l.cosInner = std::cos(glm::radians(0.5f * outerDeg));
  return l;
}

TEST(LitReach, NeverMissesAPointTheConeLightsAndMissesWhatIsClearlyOutside) {
  std::mt19937 rng(11);
  std::uniform_real_distribution<float> u(-1.0f, 1.0f), ang(2.0f, 120.0f), rad(0.0f, 0.4f);
  int missed = 0, reached = 0;
  for (int t = 0; t < 400; ++t) {
    const Light l =
        spot(Vec3(u(rng), u(rng), u(rng)), Vec3(u(rng), u(rng), u(rng)) + 1e-3f, ang(rng));
    const LitReach lit({l});
    ASSERT_FALSE(lit.everywhere());
    const Vec3 c(u(rng), u(rng), u(rng));
    const float r = rad(rng);
    const bool reaches = lit.reaches(c, r);
    reached += reaches;
    // Points of the ball, its surface included: where the cone lights one, the ball is reached.
    bool litInside = false;
    for (int i = 0; i < 2000 && !litInside; ++i) {
      Vec3 d(u(rng), u(rng), u(rng));
      if (glm::length(d) > 1.0f) continue;
      if (i % 2) d = glm::normalize(d + 1e-6f);
      Light::Incident inc;
      litInside = l.incident(c + r * d, inc);
    }
    if (litInside) {
      EXPECT_TRUE(reaches) << t;
    }
    // Clearly outside: the ball's centre more than its angular size + 0.05 rad off the cone.
    const Vec3 v = c - l.position;
    const float L = glm::length(v);
    if (L > r) {
      const float alpha = std::acos(std::clamp(glm::dot(v, l.direction) / L, -1.0f, 1.0f));
      if (alpha > std::acos(l.cosOuter) + std::asin(r / L) + 0.05f) {
        EXPECT_FALSE(reaches) << t;
        ++missed;
      }
    }
  }
  EXPECT_GT(missed, 50);  // the test decides both ways on this draw
  EXPECT_GT(reached, 50);
  Light point;
  EXPECT_TRUE(LitReach({spot(Vec3(0), Vec3(0, -1, 0), 10.0f), point}).everywhere());
  EXPECT_TRUE(LitReach({spot(Vec3(0), Vec3(0, -1, 0), 10.0f), point}).reaches(Vec3(0, 5, 0), 0));
}

/// A box of uniform fog under a narrow spot from above: most of the box is outside the cone.
Json shaftDoc() {
  Json doc = testing::homogeneousBoxDoc(1.0f, 1.5f, 0.8f, Vec3(0), 1.0f, 40, 30, 32);
  doc["lights"] = Json::parse(R"([{"type": "spot", "position": [0.45, 1.4, 0.55],
      "direction": [0.1, -1, 0], "intensity": [3, 2.5, 2], "inner_deg": 6, "outer_deg": 9}])");
  doc["camera"]["position"] = {0.5, 0.6, -1.6};
  return doc;
}

TEST(LitReach, SamplesNoConeReachesAreNotTraced) {
  const Scene scene = testing::sceneFromJson(shaftDoc());
  const DensityGrid d = buildDensityVolume(scene);
  std::vector<RadianceSample> all;
  for (int i = 0; i < 8; ++i)
    for (int j = 0; j < 8; ++j)
      for (int k = 0; k < 8; ++k) {
        RadianceSample s;
        s.position = (Vec3(i, j, k) + 0.5f) / 8.0f;
        s.radius = 0.1f;
        all.push_back(s);
      }
  const float h = scene.medium.voxelSize(), reach = glm::length(Vec3(h));
  const LitReach lit(scene.lights);
  for (const bool logSpace : {false, true}) {
    TracerSteps every{h, 0.5f * h, true, logSpace, true, 0.0f};
    TracerSteps skip = every;
    skip.reach = reach;
    std::vector<RadianceSample> a = all, b = all;
    evaluateSamples(scene, d, every, a, true);
    evaluateSamples(scene, d, skip, b, true);
    int untraced = 0;
    for (std::size_t n = 0; n < all.size(); ++n) {
      if (lit.reaches(all[n].position, all[n].radius + reach)) {
        EXPECT_EQ(b[n].S, a[n].S) << n;
        for (int x = 0; x < 3; ++x) EXPECT_EQ(b[n].dS[x], a[n].dS[x]) << n;
        continue;
      }
      ++untraced;
      EXPECT_EQ(b[n].S, Vec3(logSpace ? std::log(kMinV) : 0.0f)) << n;
      for (int x = 0; x < 3; ++x) EXPECT_EQ(b[n].dS[x], Vec3(0.0f)) << n;
      // Traced, its V is the cones-ignored continuation: not 0, which is why it costs.
      EXPECT_GT(a[n].S.x, logSpace ? std::log(kMinV) : 0.0f) << n;
    }
    EXPECT_GT(untraced, int(all.size()) / 2);  // most of the box
    EXPECT_LT(untraced, int(all.size()));
    // A point without a sphere (a probe) is always traced.
    std::vector<RadianceSample> p = {all[0]};
    p[0].radius = 0.0f;
    evaluateSamples(scene, d, skip, p, false);
    EXPECT_EQ(p[0].S, a[0].S);
  }
}

TEST(LitReach, TheImageIsThatOfEverySampleTraced) {
  // The same scene with a dark point light outside the box: A, V and every sum are the same,
  // but a point light lights everything, so nothing is skipped. Gradient, adaptive and
  // adaptive's whole-scene fallback (per-voxel V) give the same image bit for bit.
  const Scene spotOnly = testing::sceneFromJson(shaftDoc());
  Json dark = shaftDoc();
  dark["lights"].push_back({{"type", "point"}, {"position", {3, 3, 3}}, {"intensity", 0}});
  const Scene withDark = testing::sceneFromJson(dark);
  for (const Json& r : {Json{{"method", "gradient"},
                             {"sampler", {{"type", "jittered"}, {"count", 300}}},
                             {"voxel_switch", 0}},
                        Json{{"method", "adaptive"}, {"voxel_switch", 0}},
                        Json{{"method", "adaptive"}, {"voxel_switch", 1000}}}) {
    Scene a = spotOnly, b = withDark;
    a.render = b.render = r;
    const RenderResult ra = createMethod(a)->render(a, nullptr);
    const RenderResult rb = createMethod(b)->render(b, nullptr);
    EXPECT_EQ(compareImages(ra.image, rb.image).maxAbs, 0.0) << r.dump();
    double sum = 0.0;
    for (const Vec3& px : ra.image.pixels()) sum += px.x + px.y + px.z;
    EXPECT_GT(sum, 0.0);  // the shaft is in view
    if (r.contains("voxel_switch") && r["voxel_switch"] == 1000) {
      // The fallback traced only the voxels a cone reaches.
      EXPECT_LT(ra.stats.extra["traced_voxels"].get<long long>(),
                rb.stats.extra["traced_voxels"].get<long long>() / 2);
    }
  }
}

}  // namespace
}  // namespace scatterlab
