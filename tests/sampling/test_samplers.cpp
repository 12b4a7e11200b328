// Samplers: points and valid radii (gaussian-centres, jittered, grid), determinism, coverage,
// and parameter errors.

#include <gtest/gtest.h>

#include <algorithm>

#include "core/stages.h"
#include "sampling/dynamic_sampling.h"
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

/// Which cells of a `dims` grid over the density's box hold a voxel centre with D > 0 (the
/// documented occupancy rule), by brute force over the voxel centres.
std::vector<char> cellsWithDensity(const DensityGrid& d, IVec3 dims) {
  std::vector<char> used(std::size_t(dims.x) * dims.y * dims.z, 0);
  const Vec3 cell = d.bounds().extent() / Vec3(dims);
  for (int k = 0; k < d.dims().z; ++k)
    for (int j = 0; j < d.dims().y; ++j)
      for (int i = 0; i < d.dims().x; ++i) {
        if (!(d.at(i, j, k) > 0.0f)) continue;
        const IVec3 c = glm::min(IVec3((d.cellCenter(i, j, k) - d.bounds().min) / cell), dims - 1);
        used[std::size_t(c.x + dims.x * (c.y + dims.y * c.z))] = 1;
      }
  return used;
}

/// The cell layout with `nLong` cells along the box's longest axis (cells as cubic as the box
/// allows: the documented layout of the grid and jittered samplers).
IVec3 layoutWithLongAxis(const Box& b, int nLong) {
  const Vec3 e = b.extent();
  const float h = std::max({e.x, e.y, e.z}) / float(nLong);
  return glm::max(IVec3(glm::ceil(e / h - 1e-4f)), IVec3(1));
}

TEST(CellSamplers, SkipsEmptyCellsAndAimsAtTheCount) {
  const Scene scene = testing::sceneFromJson(blobsDoc());
  const DensityGrid d = buildDensityVolume(scene);
  const long long count = 200;
  const auto s = sample(scene, {{"type", "jittered"}, {"count", count}});
  const SampleCells cells = chooseSampleCells(d, count, true);
  // One sample in each cell with density, and none elsewhere.
  const std::vector<char> used = cellsWithDensity(d, cells.dims);
  ASSERT_EQ(s.size(), std::size_t(std::count(used.begin(), used.end(), 1)));
  for (const auto& x : s) {
    const IVec3 c = glm::min(IVec3((x.position - d.bounds().min) / cells.cell), cells.dims - 1);
    EXPECT_TRUE(used[std::size_t(c.x + cells.dims.x * (c.y + cells.dims.y * c.z))])
        << x.position.x << " " << x.position.y << " " << x.position.z;
  }
  // As close to the count as the layouts with one cell more or less along the long axis
  // (measured: 192 samples; 109 and 303 with one cell less and more).
  const int nLong = std::max({cells.dims.x, cells.dims.y, cells.dims.z});
  const auto miss = [&](long long n) { return std::llabs(n - count); };
  for (const int other : {nLong - 1, nLong + 1}) {
    const std::vector<char> u = cellsWithDensity(d, layoutWithLongAxis(d.bounds(), other));
    EXPECT_LE(miss((long long)s.size()), miss(std::count(u.begin(), u.end(), 1)))
        << s.size() << " samples; " << other << " cells along the long axis";
  }
  // Without skipping, every cell of a layout aimed at the count.
  const auto all = sample(scene, {{"type", "grid"}, {"count", count}, {"skip_empty", false}});
  const SampleCells allCells = chooseSampleCells(d, count, false);
  EXPECT_EQ(all.size(), std::size_t(allCells.dims.x) * allCells.dims.y * allCells.dims.z);
  EXPECT_GT(all.size(), s.size());
}

/// A host frame that counts its calls, and may say that it counts grids together (as a GPU
/// frame does).
class CountingFrame : public HostFrame {
 public:
  CountingFrame(const DensityGrid& d, bool together) : HostFrame(d), together(together) {}
  bool countsGridsTogether() const override { return together; }
  std::vector<long long> countOccupiedCells(std::span<const IVec3> grids) override {
    ++calls;
    counted += grids.size();
    return HostFrame::countOccupiedCells(grids);
  }
  bool together;
  int calls = 0;
  std::size_t counted = 0;
};

// The search that asks ahead (a frame that counts grids together) visits the bisection's grids
// and so chooses the same cells as the one that counts a grid per step, in fewer calls. The
// blobs' density is 32 voxels along its longest axis, 5 bisection steps: measured 2 calls
// asking 4 steps ahead (1 where even the finest grid has too few cells), against 6 one grid at
// a time.
TEST(CellSamplers, AskingAheadChoosesTheSameCellsInFewerCalls) {
  const Scene scene = testing::sceneFromJson(blobsDoc());
  const DensityGrid d = buildDensityVolume(scene);
  ASSERT_EQ(std::max({d.dims().x, d.dims().y, d.dims().z}), 32);
  for (const long long count : {1LL, 7LL, 190LL, 200LL, 5000LL, 1000000LL})
    for (const bool atMost : {false, true}) {
      CountingFrame plain(d, false), ahead(d, true);
      const Vec3 ext = d.bounds().extent();
      const SampleCells a = chooseSampleCells(plain, ext, d.dims(), count, true, atMost);
      const SampleCells b = chooseSampleCells(ahead, ext, d.dims(), count, true, atMost);
      EXPECT_EQ(a.dims, b.dims) << count << (atMost ? " at most" : "");
      EXPECT_EQ(a.occupied, b.occupied) << count;
      EXPECT_EQ(ahead.calls, count < 1000000 ? 2 : 1) << count;
      if (count < 1000000) {
        EXPECT_EQ(plain.calls, 6) << count;
      }
    }
}

TEST(CellSamplers, AtMostMakesTheCountACeiling) {
  // 200 aimed at gives 192 (the test above); 190 aimed at gives the nearest, 192, above it, and
  // with at_most the finest layout with at most 190: 109 (one cell less along the long axis).
  const Scene scene = testing::sceneFromJson(blobsDoc());
  const auto nearest = sample(scene, {{"type", "jittered"}, {"count", 190}});
  const auto ceiling = sample(scene, {{"type", "jittered"}, {"count", 190}, {"at_most", true}});
  EXPECT_EQ(nearest.size(), 192u);
  EXPECT_EQ(ceiling.size(), 109u);
  // A count the layout meets exactly is kept either way.
  EXPECT_EQ(sample(scene, {{"type", "grid"}, {"count", 192}, {"at_most", true}}).size(), 192u);
  // gradient's default sampler is jittered with at most adaptive's budget cap.
  const auto cap = sample(scene, {{"type", "jittered"}, {"count", kBudgetCap}, {"at_most", true}});
  EXPECT_LE(cap.size(), std::size_t(kBudgetCap));
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
