/// A render's plan, checked when its method is created and before anything is built
/// (checkRenderPlan, docs/reliability.md): the sum of its planned allocations against the
/// memory limit, and the light-march work of evaluating its samples against kMaxLightSteps.

#include <gtest/gtest.h>

#include <string>
#include <vector>

#include "api/scatterlab.h"
#include "core/limits.h"
#include "core/method.h"
#include "core/scene.h"
#include "core/work_limits.h"
#include "support/scenes.h"

namespace scatterlab {
namespace {

using testing::kGlow;

/// Sets the process's memory limit for one test and restores the default after it.
struct MemoryLimit {
  explicit MemoryLimit(std::uint64_t bytes) { setMemoryLimit(bytes); }
  ~MemoryLimit() { setMemoryLimit(0); }
};

/// The LimitError message of creating `method` on the CPU for glow.json with `sets`, "" when
/// it is created.
std::string limitOf(const std::string& method, const std::vector<std::string>& sets) {
  initialize();
  const Scene scene = loadScene(kGlow, sets);
  try {
    (void)createMethod(scene, method, "cpu");
  } catch (const LimitError& e) {
    return e.what();
  }
  return "";
}

bool has(const std::string& text, const std::string& part) {
  return text.find(part) != std::string::npos;
}

constexpr std::uint64_t kMiB = std::uint64_t(1) << 20;

}  // namespace

TEST(RenderPlan, TheSumOfTheAllocationsIsCheckedNotOnlyEachOne) {
  // per-voxel at 128^3 (glow's resolution): density 8 MiB, radiance 24 MiB, the fast march's
  // fused volume 32 MiB, and 2.4 MiB more (the 320x240 image, the max-density grid, the
  // Gaussians): 66 MiB in all, each below 48 MiB.
  const std::vector<std::string> sets = {"medium.resolution=128"};
  {
    const MemoryLimit limit(48 * kMiB);  // above the largest single allocation (32 MiB)
    const std::string m = limitOf("per-voxel", sets);
    EXPECT_TRUE(has(m,
                    "the render's planned allocations need about 66 MiB in all, above the "
                    "memory limit of 48 MiB"))
        << m;
    // The largest contributors, largest first, with their keys.
    EXPECT_TRUE(has(m,
                    "the largest: 'render.fast_march': the fused density + radiance volume "
                    "of 128x128x128 voxels, 32 MiB; 'render.radiance_resolution': the "
                    "source-radiance volume of 128x128x128 voxels, 24 MiB; "
                    "'medium.resolution': the density volume of 128x128x128 voxels, 8.0 MiB; "
                    "and 3 smaller, 2.4 MiB"))
        << m;
  }
  {
    const MemoryLimit limit(80 * kMiB);  // above the total: created
    EXPECT_EQ(limitOf("per-voxel", sets), "");
  }
  {
    // Without the fused volume (fast_march = false) the same render needs 34 MiB.
    const MemoryLimit limit(48 * kMiB);
    EXPECT_EQ(limitOf("per-voxel", {"medium.resolution=128", "render.fast_march=false"}), "");
  }
}

TEST(RenderPlan, DynamicSamplingBuffersCount) {
  // adaptive, 1e5 grid samples at level 0 with 40 probes each: 1e5 x 40 x 72 bytes = 275 MiB
  // of probes, beside the 128^3 volumes (64 MiB) and 12 MiB more: 351 MiB in all.
  const MemoryLimit limit(300 * kMiB);
  const std::string m =
      limitOf("adaptive", {"render.sampler={\"type\": \"grid\", \"count\": 100000}"});
  EXPECT_TRUE(has(m,
                  "need about 351 MiB in all, above the memory limit of 300 MiB; the largest: "
                  "'render.probes': the "
                  "probes of 100000 level-0 samples (40 each), 275 MiB"))
      << m;
}

TEST(RenderPlan, AsFarFieldGridCountsBesideTheFusedVolume) {
  // gradient at 128^3 with render.far_field: a grid of 129^3 RGB vertices (24.6 MiB) beside the
  // density (8 MiB), radiance (24 MiB) and fused (32 MiB) volumes: the fast march takes it too;
  // with fast_march false the fused volume is not held.
  const MemoryLimit limit(40 * kMiB);  // above each, below the sum
  const std::string m = limitOf("gradient", {"medium.resolution=128", "render.far_field=16"});
  EXPECT_TRUE(has(m, "'render.far_field': A's far field of 129x129x129 vertices, 25 MiB")) << m;
  EXPECT_TRUE(has(m, "fused density")) << m;
  const std::string plain = limitOf(
      "gradient", {"medium.resolution=128", "render.far_field=16", "render.fast_march=false"});
  EXPECT_TRUE(has(plain, "'render.far_field': A's far field")) << plain;
  EXPECT_FALSE(has(plain, "fused density")) << plain;
}

TEST(RenderPlan, SampleEvaluationWorkIsBoundedBeforeStarting) {
  // A unit box: delta1 = 2e-6 gives ceil(1.732 / 2e-6) = 866 026 steps per traced point and
  // light (glow has one light).
  // gradient: 1e6 samples x 7 points (S and 6 for the central differences of ∇S) = 6.06e12.
  const std::string g = limitOf("gradient", {"render.delta1=2e-6",
                                             "render.sampler={\"type\": "
                                             "\"jittered\", \"count\": "
                                             "1000000}"});
  EXPECT_TRUE(has(g,
                  "'render.sampler.count', 'render.delta1': evaluating 1000000 samples traces "
                  "7 points each (S, 6 for its gradient) with 8.66e+05 light-march steps each "
                  "(delta1 2e-06), 6.06e+12 steps in all, above the bound of 1e+12"))
      << g;
  // adaptive: 1e5 level-0 samples x 47 points (S, 6, 40 probes) = 4.07e12, naming the probes.
  const std::string a = limitOf("adaptive", {"render.delta1=2e-6",
                                             "render.sampler={\"type\": "
                                             "\"grid\", \"count\": "
                                             "100000}"});
  EXPECT_TRUE(has(a,
                  "'render.sampler.count', 'render.delta1', 'render.probes': evaluating "
                  "100000 samples traces 47 points each (S, 6 for its gradient, 40 probes)"))
      << a;
  EXPECT_TRUE(has(a, "4.07e+12 steps in all, above the bound of 1e+12 (level 0 alone")) << a;
  // 1e5 gradient samples: 6.06e11 steps, below the bound.
  EXPECT_EQ(limitOf("gradient", {"render.delta1=2e-6",
                                 "render.sampler={\"type\": \"jittered\", "
                                 "\"count\": 100000}"}),
            "");
}

}  // namespace scatterlab
