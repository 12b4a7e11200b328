/// The GPU variants of `jittered-march` and `froxel` (gpu/screen_march.cpp) against their CPU
/// variants (cpu/), end to end through createMethod: every jitter pattern and downsample,
/// both depth distributions and both light-transmittance sources. Scenes with objects:
/// tests/gpu/test_competitor_objects.cpp.

#include <gtest/gtest.h>

#include "core/method.h"
#include "gpu/frame.h"
#include "gpu/screen_march.h"
#include "gpu_support.h"

namespace scatterlab::testing {
namespace {

/// relative L2 of the GPU image against the CPU one for `render` keys on the blob scene (a
/// point light inside the medium, a spot above it), 40x30.
double blobGpuVsCpu(const Json& render) {
  Json doc = blobSceneDoc(24, 40, 30);
  doc["render"] = render;
  const Scene scene = sceneFromJson(doc);
  const RenderResult cpu = createMethod(scene, "", "cpu")->render(scene, nullptr);
  const RenderResult gpu = createMethod(scene, "", "gpu")->render(scene, nullptr);
  EXPECT_EQ(gpu.stats.backend, "gpu");
  EXPECT_EQ(gpu.stats.extra.value("steps", Json()), cpu.stats.extra.value("steps", Json()));
  const double e = relL2(gpu.image, cpu.image);
  std::printf("%s: gpu vs cpu relative L2 %.3g\n", render.dump().c_str(), e);
  return e;
}

TEST(GpuJitteredMarch, MatchesCpuForEveryJitterAndDownsample) {
  SCATTERLAB_REQUIRE_GPU();
  const std::string m = "jittered-march";
  // Measured on llvmpipe: 9.5e-7, 4.2e-7, 1.1e-6, 1.5e-6 (float rounding of exp and of the
  // IGN's fract; per-pixel work, so deterministic); on an NVIDIA H200 (driver 580), 2026-11, issue
  // 23: up to 3.3e-6 (hardware exp). Limit 1.5x the largest.
  for (const Json& r : {Json{{"method", m}}, Json{{"method", m}, {"jitter", "none"}, {"steps", 7}},
                        Json{{"method", m}, {"jitter", "blue-noise"}, {"downsample", 2}},
                        Json{{"method", m}, {"jitter", "ign"}, {"downsample", 4}}})
    EXPECT_LT(blobGpuVsCpu(r), 5.0e-6) << r.dump();
}

TEST(GpuFroxel, MatchesCpuForBothDistributionsAndTransmittances) {
  SCATTERLAB_REQUIRE_GPU();
  const std::string m = "froxel";
  // Measured on llvmpipe (slices clipped to the box, 2026-12-07): 4.7e-7, 3.2e-6, 3.3e-7 (float
  // rounding of pow, log and exp); with SCATTERLAB_GPU_IMPRECISE=4 1.5e-6, 2.7e-6, 3.8e-7; on an
  // NVIDIA H200 (driver 580, unclipped), 2026-11, issue 23: up to 2.8e-6. Since the rays are the
  // CPU's (cpu_arithmetic.glsl) and the slices' depths the host's (2026-12-08): 9.3e-8, 1.1e-7,
  // 3.4e-7; N = 4 1.2e-7, 8.9e-7, 3.9e-7. Limit 1.5x the largest, the H200's (not re-measured).
  for (const Json& r :
       {Json{{"method", m}, {"froxel_grid", {20, 15, 32}}},
        Json{{"method", m}, {"froxel_grid", {40, 30, 16}}, {"depth_distribution", "linear"}},
        Json{{"method", m},
             {"froxel_grid", {13, 11, 24}},
             {"light_transmittance", "map"},
             {"transmittance_map_resolution", 16}}})
    EXPECT_LT(blobGpuVsCpu(r), 4.2e-6) << r.dump();
}

// On a driver that caps loop iterations (llvmpipe) the lights are split over dispatches
// (gpu::lightDispatches; before, froxel and jittered-march with ~100 lights on llvmpipe, and
// data/scenes/lamps32.json at its defaults, were the loop guard's GpuError). Forced here on the
// blob scene with two more lamps (4 lights, 3 dispatches: lights {0, 3}, {1}, {2}): each
// dispatch adds its part to what the ones before stored, the image is one pass's to float
// rounding, and the pass's dispatches are counted.
TEST(GpuScreenMarches, LightsSplitOverDispatchesAddUpToOnePass) {
  SCATTERLAB_REQUIRE_GPU();
  Json doc = blobSceneDoc(24, 40, 30);
  addRingOfLamps(doc, 2, 0.3, 0.5, {0.4, 0.3, 0.2});
  for (const Json& r :
       {Json{{"method", "jittered-march"}}, Json{{"method", "jittered-march"}, {"downsample", 2}},
        Json{{"method", "froxel"}, {"froxel_grid", {20, 15, 32}}},
        Json{{"method", "froxel"},
             {"froxel_grid", {13, 11, 24}},
             {"light_transmittance", "map"},
             {"transmittance_map_resolution", 16}}}) {
    doc["render"] = r;
    ASSERT_EQ(sceneFromJson(doc).lights.size(), 4u);
    const std::string pass = r["method"] == "froxel" ? "froxel accumulate" : "jittered march";
    const RenderResult one = renderSplittingLights(doc, 1);
    const RenderResult split = renderSplittingLights(doc, 3);
    const auto dispatches = [&](const RenderResult& res) {
      return res.stats.extra.at("dispatches_by_pass").value(pass, 0);
    };
    EXPECT_EQ(dispatches(one), 1) << r.dump();
    EXPECT_EQ(dispatches(split), 3) << r.dump();
    const double e = relL2(split.image, one.image);
    std::printf("%s: split over 3 dispatches vs one, relative L2 %.3g\n", r.dump().c_str(), e);
    // Measured on llvmpipe 2026-12-07: 1.44e-7, 8.2e-8, 8.8e-8, 7.7e-8 (the parts' sums
    // rounded in another order; the arithmetic of each term is the same on any device).
    EXPECT_LT(e, 2.2e-7) << r.dump();
  }
}

}  // namespace
}  // namespace scatterlab::testing
