// Dusty room, Perlin improved noise and the time parameter of the procedural models.

#include <gtest/gtest.h>

#include "api/scatterlab.h"
#include "media/procedural.h"
#include "support/scenes.h"

namespace scatterlab {
namespace {

TEST(PerlinNoise, ReferenceValuesAndLatticeZeros) {
  const PerlinNoise n(0);
  // Value of Perlin's Java reference implementation, ImprovedNoise.noise(3.14, 42, 7).
  EXPECT_NEAR(n.noise(3.14, 42, 7), 0.13691995878400012, 1e-12);
  EXPECT_EQ(n.noise(1, 2, 3), 0.0);
  double lo = 1, hi = -1;
  for (int i = 0; i < 4000; ++i) {
    const double v = n.noise(i * 0.137, i * 0.071, i * 0.219);
    lo = std::min(lo, v);
    hi = std::max(hi, v);
  }
  EXPECT_GE(lo, -1.05);
  EXPECT_LE(hi, 1.05);
  EXPECT_LT(lo, -0.3);
  EXPECT_GT(hi, 0.3);
  // Another seed shuffles the permutation: still zero on the lattice. With y and z on the
  // lattice the noise is lerp(fade(fx), g0, g1) of the gradients at the two x corners; seed 7's
  // shuffle (the same on every platform) picks g0 = −fx and g1 = −(fx − 1), so the value is
  // −fx + fade(fx) = −0.1179997056 (seed 0 picks g0 = fx, g1 = 0: the reference value above).
  const PerlinNoise seven(7);
  EXPECT_EQ(seven.noise(1, 2, 3), 0.0);
  const double fx = 3.14 - 3, fade = fx * fx * fx * (fx * (fx * 6 - 15) + 10);
  EXPECT_DOUBLE_EQ(seven.noise(3.14, 42, 7), -fx + fade);
  EXPECT_DOUBLE_EQ(n.noise(3.14, 42, 7), fx - fade * fx);
}

Json doc(const Json& density) {
  return Json{
      {"medium",
       {{"bounds", {{"min", {0, 0, 0}}, {"max", {2, 1, 2}}}},
        {"density", density},
        {"resolution", 8}}},
      {"lights", Json::array({{{"type", "point"}, {"position", {1, 0.5, 1}}, {"intensity", 1}}})},
      {"camera", {{"position", {1, 0.5, -3}}, {"look_at", {1, 0.5, 1}}}}};
}

TEST(DustyRoom, FloorToCeilingGradientWithNoise) {
  const Scene plain = testing::sceneFromJson(doc({{"type", "dusty-room"}, {"amplitude", 0}}));
  EXPECT_NEAR(plain.medium.density->eval(Vec3(1, 0, 1)), 0.6f, 1e-6f);
  EXPECT_NEAR(plain.medium.density->eval(Vec3(1, 1, 1)), 0.3f, 1e-6f);
  EXPECT_NEAR(plain.medium.density->eval(Vec3(1, 0.5f, 1)), 0.45f, 1e-6f);
  const Scene noisy = testing::sceneFromJson(doc({{"type", "dusty-room"}, {"amplitude", 0.1}}));
  // D = lerp(floor, ceiling, y) + amplitude · fbm(frequency · (x − min)) with the defaults
  // floor 0.6, ceiling 0.3, frequency 4, 3 octaves, seed 0 (time 0: the wind does not matter).
  const PerlinNoise perlin(0);
  double dev = 0;
  for (int i = 0; i < 500; ++i) {
    const Vec3 x(0.003f * i + 0.1f, 0.5f, 0.0037f * i + 0.2f);
    const float d = noisy.medium.density->eval(x);
    const Vec3 q = 4.0f * x;
    const float n = float(perlin.fbm(q.x, q.y, q.z, 3));
    EXPECT_FLOAT_EQ(d, 0.6f + (0.3f - 0.6f) * 0.5f + 0.1f * n) << i;
    dev += std::abs(d - 0.45f);
  }
  // The noise is there: mean |D − 0.45| measured 0.0110 (2026-11-23, this line); ÷1.5.
  EXPECT_GT(dev / 500, 0.0073);
}

TEST(DustyRoom, TimeMovesTheNoiseWithTheWind) {
  const Json base = {{"type", "dusty-room"}, {"wind", {0.5, 0, 0}}, {"frequency", 3}};
  Json later = base;
  later["time"] = 2.0;
  const Scene a = testing::sceneFromJson(doc(base));
  const Scene b = testing::sceneFromJson(doc(later));
  // At t = 2 the pattern has moved by wind · t = (1, 0, 0); same height, so same gradient.
  for (float x = 0.0f; x < 0.9f; x += 0.1f)
    EXPECT_NEAR(b.medium.density->eval(Vec3(x + 1, 0.4f, 0.7f)),
                a.medium.density->eval(Vec3(x, 0.4f, 0.7f)), 1e-5f);
  EXPECT_NE(b.medium.density->eval(Vec3(0.33f, 0.4f, 0.7f)),
            a.medium.density->eval(Vec3(0.33f, 0.4f, 0.7f)));
}

TEST(ProceduralTime, BlobsDriftAndUniformChanges) {
  const Scene s = testing::sceneFromJson(doc(
      {{"type", "gaussians"},
       {"time", 2},
       {"blobs", {{{"center", {0.5, 0.5, 0.5}}, {"radius", 0.1}, {"velocity", {0.25, 0, 0}}}}}}));
  EXPECT_NEAR(s.medium.density->eval(Vec3(1.0f, 0.5f, 0.5f)), 1.0f, 1e-6f);
  const Scene u = testing::sceneFromJson(
      doc({{"type", "uniform"}, {"value", 1}, {"rate", -0.25}, {"time", 2}}));
  EXPECT_NEAR(u.medium.density->eval(Vec3(0.5f)), 0.5f, 1e-6f);
}

TEST(DustyRoom, BadKeysNamed) {
  try {
    testing::sceneFromJson(doc({{"type", "dusty-room"}, {"octaves", 12}}));
    FAIL();
  } catch (const ConfigError& e) {
    EXPECT_NE(std::string(e.what()).find("medium.density.octaves"), std::string::npos) << e.what();
  }
  EXPECT_THROW(testing::sceneFromJson(doc({{"type", "dusty-room"}, {"frequency", 0}})),
               ConfigError);
  EXPECT_THROW(testing::sceneFromJson(doc({{"type", "dusty-room"}, {"speed", 1}})), ConfigError);
}

TEST(DensityPeak, TheLargestDensityOfEachModel) {
  EXPECT_EQ(UniformDensity(0.7f).peak(), 0.7f);
  // Two blobs far apart: the larger weight; two equal blobs one radius apart: the sum at a
  // centre, 1 + e^−1 = 1.368 (the true peak, between them, is 2·e^−1/4 = 1.558: 12 % lower).
  EXPECT_FLOAT_EQ(*GaussianDensity({{Vec3(0.2f), 0.05f, 1.5f}, {Vec3(0.8f), 0.05f, 0.7f}}).peak(),
                  1.5f);
  const GaussianDensity pair(
      {{Vec3(0.4f, 0.5f, 0.5f), 0.1f, 1.0f}, {Vec3(0.5f, 0.5f, 0.5f), 0.1f, 1.0f}});
  EXPECT_NEAR(*pair.peak(), 1.0f + std::exp(-1.0f), 1e-6f);
  EXPECT_NEAR(pair.eval(Vec3(0.45f, 0.5f, 0.5f)), 2.0f * std::exp(-0.25f), 1e-6f);
}

}  // namespace
}  // namespace scatterlab
