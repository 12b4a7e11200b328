/// The `adaptive` method (paper Sec. 5) end to end on a small light-shaft scene, as the paper
/// has it (render.paper: the absolute ε of Eq. 5 on S; the extensions are tested in
/// tests/cpu/test_fidelity.cpp).

#include <gtest/gtest.h>

#include <cstdio>

#include "support/scenes.h"

using namespace scatterlab;

namespace {

Scene shaft(int resolution) {
  initialize();
  return loadScene(
      std::string(SCATTERLAB_SOURCE_DIR) + "/data/scenes/shaft.json",
      {"medium.resolution=" + std::to_string(resolution), "camera.width=80", "camera.height=60"});
}

RenderResult renderWith(Scene s, const Json& settings) {
  s.render = settings;
  if (s.render["method"] != "exact") s.render["paper"] = true;
  return createMethod(s)->render(s, nullptr);
}

}  // namespace

TEST(Adaptive, HalvesTheErrorOfInitialSamplesOnALightShaft) {
  const Scene s = shaft(64);
  const Image ref = renderWith(s, {{"method", "exact"}}).image;
  const Json sampler = {{"type", "grid"}, {"count", 541}};
  const RenderResult g = renderWith(s, {{"method", "gradient"}, {"sampler", sampler}});
  const RenderResult a =
      renderWith(s, {{"method", "adaptive"}, {"sampler", sampler}, {"epsilon", 1e-4}});
  const double eg = compareImages(g.image, ref).relL2, ea = compareImages(a.image, ref).relL2;
  std::printf("gradient %lld samples %.2f%%, adaptive %lld samples %.2f%%\n", *g.stats.samples,
              100 * eg, *a.stats.samples, 100 * ea);
  EXPECT_LT(ea, 0.5 * eg);
  EXPECT_LE(*a.stats.samples, 4000);
  EXPECT_GT(*a.stats.samples, *g.stats.samples);
  // Stats: samples per level sum to the total; the levels are the default 16, 32 (64³ volume).
  const Json j = a.stats.toJson();
  long long sum = 0;
  for (const auto& n : j["samples_per_level"]) sum += n.get<long long>();
  EXPECT_EQ(sum, *a.stats.samples);
  ASSERT_EQ(j["levels"].size(), 3u);
  EXPECT_EQ(j["levels"][1]["grid"], 16);
  EXPECT_EQ(j["levels"][2]["grid"], 32);
  for (const char* stage : {"density", "sampling", "dynamic_sampling", "reconstruction", "march"})
    EXPECT_TRUE(j["timings_ms"].contains(stage)) << stage;
  EXPECT_EQ(a.samples.size(), std::size_t(*a.stats.samples));
}

TEST(Adaptive, MoreProbesCatchTheShaftEdgeBetweenAxisProbes) {
  const Scene s = shaft(64);
  const Image ref = renderWith(s, {{"method", "exact"}}).image;
  const Json sampler = {{"type", "grid"}, {"count", 541}};
  const double e6 =
      compareImages(
          renderWith(s, {{"method", "adaptive"}, {"sampler", sampler}, {"epsilon", 1e-4}}).image,
          ref)
          .relL2;
  const double e26 =
      compareImages(
          renderWith(
              s, {{"method", "adaptive"}, {"sampler", sampler}, {"epsilon", 1e-4}, {"probes", 26}})
              .image,
          ref)
          .relL2;
  std::printf("probes 6: rel L2 %.4f, probes 26: %.4f\n", e6, e26);
  // Measured: e6 = 0.220, e26 = 0.150 (ratio 0.68; the CPU path is deterministic). The bound
  // asks for at least a fifth of the error gone, not merely any improvement.
  EXPECT_LT(e26, 0.8 * e6) << "e6 " << e6 << ", e26 " << e26;
}

TEST(Adaptive, InfiniteEpsilonEqualsGradientWithTheInitialSamples) {
  const Scene s = shaft(32);
  const Json sampler = {{"type", "grid"}, {"count", 200}};
  const RenderResult g = renderWith(s, {{"method", "gradient"}, {"sampler", sampler}});
  const RenderResult a =
      renderWith(s, {{"method", "adaptive"}, {"sampler", sampler}, {"epsilon", 1e30}});
  EXPECT_EQ(*a.stats.samples, *g.stats.samples);
  EXPECT_LT(compareImages(a.image, g.image).maxAbs, 1e-6);
}

TEST(Adaptive, BadSettingsNameTheKey) {
  Scene s = shaft(32);
  for (const auto& [key, value] : std::vector<std::pair<std::string, Json>>{
           {"epsilon", -1}, {"levels", {8, 4}}, {"levels", {8, 32}}, {"probes", 7}, {"tau", "x"}}) {
    s.render = {{"method", "adaptive"}, {key, value}};
    try {
      createMethod(s);
      FAIL() << key;
    } catch (const ConfigError& e) {
      EXPECT_NE(std::string(e.what()).find("render." + key), std::string::npos) << e.what();
    }
  }
}
