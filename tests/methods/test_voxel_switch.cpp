/// The whole-scene fallback of `adaptive` and `gradient` (key voxel_switch, docs/fidelity.md): a
/// medium so sparse that per-voxel traces less than the method's samples would is rendered as
/// per-voxel renders it — its stages, its image bit for bit — and the rule is the one documented.

#include <algorithm>

#include "sampling/dynamic_sampling.h"
#include "shading/transport.h"
#include "support/scenes.h"

namespace scatterlab::testing {
namespace {

/// A wisp: one small blob (radius 0.05) in a unit box at 48³, a point light inside the box near
/// it (where interpolating V = S / A, not S, matters).
Json wispDoc() {
  Json doc = homogeneousBoxDoc(1.0f, 8.0f, 0.8f, Vec3(0.5f, 0.62f, 0.5f), 0.2f, 40, 30, 48);
  doc["medium"]["density"] = {
      {"type", "gaussians"},
      {"blobs", Json::array({{{"center", {0.5, 0.5, 0.5}}, {"radius", 0.05}, {"weight", 1.0}}})}};
  return doc;
}

RenderResult render(Json doc, const std::string& method, const std::string& sets = "") {
  if (!sets.empty()) applyOverride(doc, sets);
  const Scene s = sceneFromJson(doc);
  return createMethod(s, method, "cpu")->render(s, nullptr);
}

std::vector<std::string> stages(const RenderResult& r) {
  std::vector<std::string> got;
  for (const auto& [stage, ms] : r.stats.timingsMs) got.push_back(stage);
  return got;
}

/// Fog filling a 32³ box under a narrow spot: every voxel occupied, few of them lit.
Json shaftDoc() {
  Json doc = homogeneousBoxDoc(1.0f, 1.5f, 0.8f, Vec3(0), 1.0f, 40, 30, 32);
  doc["lights"] = Json::parse(R"([{"type": "spot", "position": [0.45, 1.4, 0.55],
      "direction": [0.1, -1, 0], "intensity": [3, 2.5, 2], "inner_deg": 6, "outer_deg": 9}])");
  doc["camera"]["position"] = {0.5, 0.6, -1.6};
  doc["render"]["sampler"] = {{"type", "grid"}, {"count", 100}};
  doc["render"]["voxel_switch"] = 2;
  return doc;
}

TEST(VoxelSwitch, WhereOnlySpotsShinePerVoxelTracesWhatTheConesReach) {
  // Per-voxel traces the occupied voxels a light reaches: under spot lights only, at most the
  // voxels a cone reaches (LitReach::voxelBound). 32 768 voxels are occupied, more than
  // voxel_switch × the first level's traces (2 × 125 × 41 = 10 250), but the cone reaches fewer
  // (6 912 by the bound): the scene switches; with a dark point light added (it lights
  // everything, the image is the same) it does not.
  const Scene scene = sceneFromJson(shaftDoc());
  const RenderResult spot = render(shaftDoc(), "adaptive");
  const long long bound = LitReach(scene.lights).voxelBound(scene.medium.bounds, IVec3(32));
  EXPECT_EQ(spot.stats.extra.at("occupied_voxels").get<long long>(), 32 * 32 * 32);
  EXPECT_EQ(spot.stats.extra.at("lit_voxels").get<long long>(), bound);
  EXPECT_LT(bound, 32 * 32 * 32 / 4);
  EXPECT_TRUE(spot.stats.extra.at("voxels_instead").get<bool>());
  Json dark = shaftDoc();
  dark["lights"].push_back({{"type", "point"}, {"position", {3, 3, 3}}, {"intensity", 0}});
  const RenderResult all = render(dark, "adaptive");
  EXPECT_FALSE(all.stats.extra.contains("lit_voxels"));
  EXPECT_FALSE(all.stats.extra.at("voxels_instead").get<bool>());
  // The bound holds every voxel a cone reaches (the per-voxel fallback's test, voxel by voxel).
  const LitReach lit(scene.lights);
  const Vec3 cell = scene.medium.bounds.extent() / 32.0f;
  long long reached = 0;
  for (int z = 0; z < 32; ++z)
    for (int y = 0; y < 32; ++y)
      for (int x = 0; x < 32; ++x)
        reached +=
            lit.reaches(scene.medium.bounds.min + (Vec3(x, y, z) + 0.5f) * cell, glm::length(cell));
  EXPECT_GT(reached, 0);
  EXPECT_GE(bound, reached);
  EXPECT_LT(bound, 3 * reached);  // blocks of 2³ voxels, not the whole box
}

TEST(VoxelSwitch, TheCostBudgetIsAShareOfTheVoxelsPerVoxelTraces) {
  // adaptive's cost budget (key `budget`) is a share of per-voxel's S evaluations: the voxels
  // the switch rule counted (under the spot, the bound of those the cone reaches), in radiance
  // voxels; with voxel_switch 0 nothing is counted and every radiance voxel counts. Eight
  // initial samples, so that the count rule's floor (4 × 8 = 32) is below the cost cap.
  Json doc = shaftDoc();
  doc["render"]["sampler"]["count"] = 8;
  doc["render"]["voxel_switch"] = 0.01;  // never switches here
  const Scene scene = sceneFromJson(doc);
  const long long bound = LitReach(scene.lights).voxelBound(scene.medium.bounds, IVec3(32));
  const RenderResult lit = render(doc, "adaptive");
  EXPECT_FALSE(lit.stats.extra.at("voxels_instead").get<bool>());
  EXPECT_EQ(lit.stats.extra.at("budget_voxels").get<long long>(), bound);
  EXPECT_EQ(lit.stats.extra.at("budget").get<long long>(), (long long)(0.75 * bound / 47.0));
  // A radiance volume twice as fine per axis: 8 radiance voxels per counted density voxel.
  const RenderResult fine = render(doc, "adaptive", "render.radiance_resolution=64");
  EXPECT_EQ(fine.stats.extra.at("budget_voxels").get<long long>(), 8 * bound);
  const RenderResult whole = render(doc, "adaptive", "render.voxel_switch=0");
  EXPECT_FALSE(whole.stats.extra.contains("budget_voxels"));
  EXPECT_EQ(whole.stats.extra.at("budget").get<long long>(), (long long)(0.75 * 32768 / 47.0));
}

TEST(VoxelSwitch, TheConesBoundCountsTheOccupiedVoxelsOfTheCellsTheyReach) {
  // A blob in the shaft's box: the cells at its edge are partly filled. Counting their occupied
  // voxels instead of all of them keeps a bound (at least every occupied voxel a cone reaches,
  // voxel by voxel) and tightens it (measured 2026-11-28, CPU, 96³: 69 551 by the counts against
  // 73 089 by whole cells, 53 388 reached of 172 820 occupied).
  Json doc = shaftDoc();
  doc["medium"]["density"] = {
      {"type", "gaussians"},
      {"blobs", Json::array({{{"center", {0.5, 0.45, 0.5}}, {"radius", 0.12}, {"weight", 1.0}}})}};
  doc["medium"]["resolution"] = 96;  // cells of 3³ voxels (the bound's grid is at most 32³)
  const Scene scene = sceneFromJson(doc);
  DensityGrid d(scene.medium.bounds, scene.medium.resolution);
  scene.medium.density->build(d);
  const IVec3 res = scene.medium.resolution, cells = LitReach::boundCells(res);
  const LitReach lit(scene.lights);
  const std::vector<int> counts = occupiedVoxelsPerCell(d, cells);
  std::vector<int> any(counts.size());  // the bound before: every voxel of an occupied cell
  for (std::size_t c = 0; c < counts.size(); ++c) any[c] = counts[c] > 0 ? 1 << 30 : 0;
  const long long whole = lit.voxelBound(scene.medium.bounds, res, &any);
  const long long bound = lit.voxelBound(scene.medium.bounds, res, &counts);
  const Vec3 cell = scene.medium.bounds.extent() / Vec3(res);
  long long reached = 0, occupied = 0;
  for (int z = 0; z < res.z; ++z)
    for (int y = 0; y < res.y; ++y)
      for (int x = 0; x < res.x; ++x) {
        if (!(d.at(x, y, z) > 0.0f)) continue;
        ++occupied;
        reached +=
            lit.reaches(scene.medium.bounds.min + (Vec3(x, y, z) + 0.5f) * cell, glm::length(cell));
      }
  std::printf("occupied %lld, reached %lld, bound by counts %lld, by whole cells %lld\n", occupied,
              reached, bound, whole);
  EXPECT_GT(reached, 0);
  EXPECT_GE(bound, reached);
  EXPECT_LT(bound, whole);
  EXPECT_EQ(render(doc, "adaptive").stats.extra.at("lit_voxels").get<long long>(), bound);
}

TEST(VoxelSwitch, ASparseMediumIsRenderedAsPerVoxelRendersIt) {
  const RenderResult perVoxel = render(wispDoc(), "per-voxel");
  const RenderResult adaptive = render(wispDoc(), "adaptive");
  const RenderResult exact = render(wispDoc(), "exact");
  EXPECT_TRUE(adaptive.stats.extra.at("voxels_instead").get<bool>());
  // The count the rule saw: the density's voxels with D > 0.
  ASSERT_TRUE(adaptive.density);
  const auto& d = adaptive.density->data();
  const long long occupied = std::count_if(d.begin(), d.end(), [](float v) { return v > 0.0f; });
  EXPECT_EQ(adaptive.stats.extra.at("occupied_voxels").get<long long>(), occupied);
  EXPECT_LT(occupied, 48 * 48 * 48 / 4);
  EXPECT_EQ(stages(adaptive), (std::vector<std::string>{"density", "radiance", "march"}));
  EXPECT_EQ(adaptive.stats.extra.at("traced_voxels"), perVoxel.stats.extra.at("traced_voxels"));
  EXPECT_EQ(*adaptive.stats.samples, 0);
  // Per-voxel's voxels, holding V = S / A (factor_lights) for the factored march: against exact
  // better than per-voxel's S near the lamp.
  EXPECT_TRUE(adaptive.stats.extra.at("factor_lights").get<bool>());
  const double own = compareImages(adaptive.image, exact.image).relL2;
  const double pv = compareImages(perVoxel.image, exact.image).relL2;
  std::printf("against exact: adaptive (per-voxel of V) %.4g, per-voxel %.4g\n", own, pv);
  // Measured 2026-11-28: 0.005535 against per-voxel's 0.03003 (CPU).
  EXPECT_LT(own, 0.0083);
  EXPECT_LT(own, pv);
  // Off: dynamic sampling, another image.
  const RenderResult refined = render(wispDoc(), "adaptive", "render.voxel_switch=0");
  EXPECT_FALSE(refined.stats.extra.at("voxels_instead").get<bool>());
  EXPECT_EQ(stages(refined), (std::vector<std::string>{"density", "sampling", "dynamic_sampling",
                                                       "reconstruction", "march"}));
  EXPECT_GT(*refined.stats.samples, 0);
  EXPECT_GT(compareImages(refined.image, perVoxel.image).maxAbs, 0.0);
  // The paper's algorithm never switches.
  const RenderResult paper = render(wispDoc(), "adaptive", "render.paper=true");
  EXPECT_FALSE(paper.stats.extra.at("voxels_instead").get<bool>());
}

TEST(VoxelSwitch, GradientFallsBackAsAdaptiveDoesWhereItsSamplesTraceMore) {
  // gradient's sampled path traces 7 points per sample (S and the six differences of ∇S): its
  // default 8 000 jittered samples at most on the wisp's 48³ box trace far more than the few
  // thousand voxels holding density, so it renders as per-voxel renders them: the same image as
  // adaptive's fallback (the same V = S / A per voxel, the same march).
  const RenderResult adaptive = render(wispDoc(), "adaptive");
  const RenderResult gradient = render(wispDoc(), "gradient");
  EXPECT_TRUE(gradient.stats.extra.at("voxels_instead").get<bool>());
  EXPECT_EQ(stages(gradient), (std::vector<std::string>{"density", "radiance", "march"}));
  EXPECT_EQ(*gradient.stats.samples, 0);
  EXPECT_EQ(compareImages(gradient.image, adaptive.image).maxAbs, 0.0);
  // The rule's edge, with the Gaussian centres (one sample: 7 traces): voxel_switch × 7 against
  // the occupied voxels.
  const long long occupied = gradient.stats.extra.at("occupied_voxels").get<long long>();
  ASSERT_LT(occupied, 7000);  // within the key's range of 1000 × 7
  const auto centres = [&](double k) {
    Json doc = wispDoc();
    doc["render"]["sampler"] = {{"type", "gaussian-centres"}};
    doc["render"]["voxel_switch"] = k;
    return render(doc, "gradient");
  };
  const double edge = double(occupied) / 7.0;
  EXPECT_TRUE(centres(edge).stats.extra.at("voxels_instead").get<bool>());
  const RenderResult below = centres(edge * (1.0 - 1e-6));
  EXPECT_FALSE(below.stats.extra.at("voxels_instead").get<bool>());
  EXPECT_EQ(*below.stats.samples, 1);
  // Off, and under the paper's algorithm (which never switches and counts nothing): samples.
  const RenderResult off = render(wispDoc(), "gradient", "render.voxel_switch=0");
  EXPECT_FALSE(off.stats.extra.at("voxels_instead").get<bool>());
  EXPECT_FALSE(off.stats.extra.contains("occupied_voxels"));
  EXPECT_GT(*off.stats.samples, 0);
  const RenderResult paper = render(wispDoc(), "gradient", "render.paper=true");
  EXPECT_FALSE(paper.stats.extra.at("voxels_instead").get<bool>());
  EXPECT_GT(*paper.stats.samples, 0);
}

TEST(VoxelSwitch, TheRuleComparesTheLitVoxelsWithTheSamplesTraces) {
  // adaptive with 40 probes: 3 × 100 initial samples × (1 + 40 probes) = 12 300 traces.
  EXPECT_TRUE(voxelsInstead(3.0, 12300, 100 * 41.0));
  EXPECT_FALSE(voxelsInstead(3.0, 12301, 100 * 41.0));
  EXPECT_FALSE(voxelsInstead(3.0, 0, 0.0));  // no samples: nothing to compare
  EXPECT_FALSE(voxelsInstead(0.0, 1, 100 * 41.0));
}

TEST(VoxelSwitch, BadValuesAreNamed) {
  initialize();
  for (const char* bad :
       {"render.voxel_switch=-1", "render.voxel_switch=1001", "render.voxel_switch=\"many\""}) {
    Json doc = wispDoc();
    applyOverride(doc, bad);
    doc["render"]["method"] = "adaptive";
    try {
      const Scene s = sceneFromJson(doc);
      createMethod(s, "", "cpu");
      ADD_FAILURE() << bad << ": no error";
    } catch (const ConfigError& e) {
      EXPECT_NE(std::string(e.what()).find("voxel_switch"), std::string::npos) << e.what();
    }
  }
  Json doc = wispDoc();
  doc["render"] = {{"method", "adaptive"}, {"paper", true}, {"voxel_switch", 3}};
  try {
    const Scene s = sceneFromJson(doc);
    createMethod(s, "", "cpu");
    ADD_FAILURE() << "paper with voxel_switch: no error";
  } catch (const ConfigError& e) {
    EXPECT_NE(std::string(e.what()).find("extension"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace scatterlab::testing
