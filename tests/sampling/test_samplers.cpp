// Samplers: points and valid radii (gaussian-centres, jittered, grid), determinism, coverage,
// and parameter errors.

#include <gtest/gtest.h>

#include "core/stages.h"
#include "sampling/samplers.h"
#include "support/scenes.h"

namespace scatterlab {
namespace {

Json blobsDoc() {
  Json doc = testing::homogeneousBoxDoc(1.0f, 1.0f, 0.6f, Vec3(0.5f, 1.5f, 0.5f), 1.0f, 16, 12, 32);
  doc["medium"]["density"] = {{"type", "gaussians"},
                              {"blobs",
                               {{{"center", {0.3, 0.5, 0.5}}, {"radius", 0.1}, {"weight", 0.5}},
                                {{"center", {0.7, 0.5, 0.5}}, {"radius", 0.2}, {"weight", 1.0}},
                                {{"center", {0.5, 0.3, 0.4}}, {"radius", 0.05}, {"weight", 2.0}}}}};
  return doc;
}

std::vector<RadianceSample> sample(const Scene& scene, const Json& samplerParams) {
  Params p(samplerParams, "render.sampler");
  const std::string type = p.string("type");
  auto s = samplers().get(type, p.keyPath("type"))(p, scene);
  p.finish();
  RenderStats st;
  const DensityGrid d = buildDensityVolume(scene);
  return s->generate(scene, d);
}

TEST(GaussianCentres, CentresRadiiAndWeights) {
  const Scene scene = testing::sceneFromJson(blobsDoc());
  const auto s = sample(scene, {{"type", "gaussian-centres"}});
  ASSERT_EQ(s.size(), 3u);
  EXPECT_EQ(s[1].position, Vec3(0.7f, 0.5f, 0.5f));
  EXPECT_FLOAT_EQ(s[0].radius, 0.3f);  // R_j = 3 r_j
  EXPECT_FLOAT_EQ(s[1].radius, 0.6f);
  EXPECT_FLOAT_EQ(s[2].weight, 2.0f);
  const auto scaled = sample(scene, {{"type", "gaussian-centres"}, {"radius_scale", 2}});
  EXPECT_FLOAT_EQ(scaled[1].radius, 0.4f);
}

TEST(GaussianCentres, CountKeepsTheHeaviestInOrder) {
  const Scene scene = testing::sceneFromJson(blobsDoc());
  // masses w r^3: 5e-4, 8e-3, 2.5e-4 -> keep blobs 0 and 1.
  const auto s = sample(scene, {{"type", "gaussian-centres"}, {"count", 2}});
  ASSERT_EQ(s.size(), 2u);
  EXPECT_EQ(s[0].position, Vec3(0.3f, 0.5f, 0.5f));
  EXPECT_EQ(s[1].position, Vec3(0.7f, 0.5f, 0.5f));
}

TEST(GaussianCentres, NeedsGaussians) {
  const Scene scene = testing::sceneFromJson(
      testing::homogeneousBoxDoc(1.0f, 1.0f, 0.6f, Vec3(0.5f, 1.5f, 0.5f), 1.0f, 16, 12, 16));
  const Json j{{"type", "gaussian-centres"}};
  Params p(j, "render.sampler");
  p.string("type");
  try {
    samplers().get("gaussian-centres", "render.sampler.type")(p, scene);
    FAIL() << "expected ConfigError";
  } catch (const ConfigError& e) {
    EXPECT_NE(std::string(e.what()).find("render.sampler.type"), std::string::npos) << e.what();
  }
}

TEST(CellSamplers, GridCoversEveryVoxelWithTheDocumentedRadius) {
  const Scene scene = testing::sceneFromJson(
      testing::homogeneousBoxDoc(1.0f, 1.0f, 0.6f, Vec3(0.5f, 1.5f, 0.5f), 1.0f, 16, 12, 16));
  const auto s = sample(scene, {{"type", "grid"}, {"count", 64}});
  ASSERT_EQ(s.size(), 64u);  // 4^3 cells of edge 0.25
  for (const auto& x : s) {
    EXPECT_FLOAT_EQ(x.radius, 0.25f);
    EXPECT_TRUE(scene.medium.bounds.contains(x.position));
  }
  EXPECT_EQ(s[0].position, Vec3(0.125f));
  // Every voxel centre lies strictly inside some valid sphere.
  RadianceGrid g(scene.medium.bounds, IVec3(16));
  for (int k = 0; k < 16; ++k)
    for (int j = 0; j < 16; ++j)
      for (int i = 0; i < 16; ++i) {
        bool covered = false;
        for (const auto& x : s)
          covered |= glm::length(g.cellCenter(i, j, k) - x.position) < x.radius;
        ASSERT_TRUE(covered) << i << " " << j << " " << k;
      }
}

TEST(CellSamplers, JitteredIsStratifiedDeterministicAndCovering) {
  const Scene scene = testing::sceneFromJson(
      testing::homogeneousBoxDoc(1.0f, 1.0f, 0.6f, Vec3(0.5f, 1.5f, 0.5f), 1.0f, 16, 12, 16));
  const auto a = sample(scene, {{"type", "jittered"}, {"count", 27}, {"seed", 7}});
  const auto b = sample(scene, {{"type", "jittered"}, {"count", 27}, {"seed", 7}});
  const auto c = sample(scene, {{"type", "jittered"}, {"count", 27}, {"seed", 8}});
  ASSERT_EQ(a.size(), 27u);
  int differ = 0;
  for (std::size_t n = 0; n < a.size(); ++n) {
    EXPECT_EQ(a[n].position, b[n].position);
    differ += a[n].position != c[n].position;
    // One point per cell of edge 1/3.
    const IVec3 cell(glm::floor(a[n].position * 3.0f));
    EXPECT_EQ(cell.x + 3 * (cell.y + 3 * cell.z), int(n));
    EXPECT_NEAR(a[n].radius, 1.75f / 3.0f, 1e-6f);
  }
  EXPECT_GT(differ, 20);
}

TEST(CellSamplers, SkipsEmptyCellsAndAimsAtTheCount) {
  const Scene scene = testing::sceneFromJson(blobsDoc());
  const auto s = sample(scene, {{"type", "jittered"}, {"count", 200}});
  EXPECT_GT(s.size(), 140u);
  EXPECT_LT(s.size(), 260u);
  RenderStats st;
  const DensityGrid d = buildDensityVolume(scene);
  for (const auto& x : s) EXPECT_GT(d.sample(x.position) + 1e-3f, 0.0f);
  const auto all = sample(scene, {{"type", "grid"}, {"count", 200}, {"skip_empty", false}});
  EXPECT_GE(all.size(), s.size());
}

TEST(CellSamplers, BadParameters) {
  const Scene scene = testing::sceneFromJson(blobsDoc());
  const auto expectError = [&](const Json& params, const std::string& key) {
    try {
      sample(scene, params);
      ADD_FAILURE() << "expected ConfigError for " << params.dump();
    } catch (const ConfigError& e) {
      EXPECT_NE(std::string(e.what()).find(key), std::string::npos) << e.what();
    }
  };
  expectError({{"type", "jittered"}, {"count", 0}}, "render.sampler.count");
  expectError({{"type", "grid"}, {"count", -5}}, "render.sampler.count");
  expectError({{"type", "grid"}, {"count", 8}, {"bogus", 1}}, "render.sampler.bogus");
  expectError({{"type", "poisson"}}, "render.sampler.type");
  expectError({{"type", "gaussian-centres"}, {"radius_scale", 0}}, "render.sampler.radius_scale");
}

}  // namespace
}  // namespace scatterlab
