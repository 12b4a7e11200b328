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
  EXPECT_NE(PerlinNoise(7).noise(3.14, 42, 7), n.noise(3.14, 42, 7));
  EXPECT_EQ(PerlinNoise(7).noise(3.14, 42, 7), PerlinNoise(7).noise(3.14, 42, 7));
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
  double sum = 0, dev = 0;
  for (int i = 0; i < 500; ++i) {
    const Vec3 x(0.003f * i + 0.1f, 0.5f, 0.0037f * i + 0.2f);
    const float d = noisy.medium.density->eval(x);
    EXPECT_GE(d, 0.45f - 0.1f - 1e-4f);
    EXPECT_LE(d, 0.45f + 0.1f + 1e-4f);
    sum += d;
    dev += std::abs(d - 0.45f);
  }
  EXPECT_GT(dev / 500, 0.002);  // the noise is there
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

}  // namespace
}  // namespace scatterlab
