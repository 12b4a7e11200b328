/// Every method's GPU variant at the long ends of its documented ranges (issue 37): the image
/// matches the CPU's, or, on a driver that caps loop iterations per shader invocation (Mesa's
/// llvmpipe: 65 535 in all, gpu::loopIterationLimit()), the render is a GpuError naming the
/// pass and what made it long. Before the loop guard, llvmpipe returned these images 7-100 %
/// wrong with no error (march_step 2e-5: 88 % dark).

#include <gtest/gtest.h>

#include "core/error.h"
#include "core/method.h"
#include "gpu/shaders.h"
#include "gpu_support.h"

namespace scatterlab::testing {
namespace {

/// The blob scene at 16x12 (gradient with voxel_switch 0: its samples, not the whole-scene
/// fallback of so small a volume) with `lights` point lights on a ring above the medium (0: its own
/// two lights).
Json rangeScene(const Json& render, int lights) {
  Json doc = blobSceneDoc(16, 16, 12);
  doc["render"] = render;
  if (lights > 0) {
    doc["lights"] = Json::array();
    for (int i = 0; i < lights; ++i) {
      const double a = 6.283185307 * i / lights;
      doc["lights"].push_back(
          {{"type", "point"},
           {"position", {0.5 + 0.4 * std::cos(a), 0.8, 0.5 + 0.4 * std::sin(a)}},
           {"intensity", {2.0 / lights, 2.0 / lights, 2.0 / lights}}});
    }
  }
  return doc;
}

struct RangeEnd {
  const char* name;
  Json render;
  int lights;
  const char* key;  ///< what the loop cap's error must name
  double bound;     ///< the largest relative L2 against the CPU's image on hardware (below)
  double llvmpipe;  ///< measured on llvmpipe (0: refused there): its bound there, × 1.5
};

/// GoogleTest's printer gave the bytes, pointers included, and gtest_discover_tests puts the
/// printed value into ctest's names: they changed from build to build.
void PrintTo(const RangeEnd& r, std::ostream* os) {
  *os << r.name;
}

class GpuRangeEnds : public ::testing::TestWithParam<RangeEnd> {};

TEST_P(GpuRangeEnds, MatchTheCpuOrRefuseTheWork) {
  SCATTERLAB_REQUIRE_GPU();
  const RangeEnd& c = GetParam();
  const Scene scene = sceneFromJson(rangeScene(c.render, c.lights));
  RenderResult gpu;
  try {
    gpu = createMethod(scene, "", "gpu")->render(scene, nullptr);
  } catch (const GpuError& e) {
    const std::string m = e.what();
    ASSERT_GT(gpu::loopIterationLimit(), 0) << c.name << ": " << m;
    EXPECT_NE(m.find("than the driver allows (" + std::to_string(gpu::loopIterationLimit())),
              std::string::npos)
        << m;
    EXPECT_NE(m.find(c.key), std::string::npos) << m;
    std::printf("%s: refused (%s)\n", c.name, m.substr(0, m.find(" needed")).c_str());
    return;
  }
  const RenderResult cpu = createMethod(scene, "", "cpu")->render(scene, nullptr);
  const double e = relL2(gpu.image, cpu.image);
  std::printf("%s: gpu vs cpu relative L2 %.3g\n", c.name, e);
  // llvmpipe is the driver with the loop cap (gpu::loopIterationLimit() > 0); with a GPU's
  // approximate built-ins simulated (SCATTERLAB_GPU_IMPRECISE) it is held to a GPU's bound
  // (per_voxel_short_step: 3.9e-7 / 9.0e-7 at 2 / 4 ulps, 2026-12-07).
  const bool llvmpipeArithmetic = gpu::loopIterationLimit() > 0 && gpu::impreciseUlps() == 0;
  EXPECT_LT(e, llvmpipeArithmetic && c.llvmpipe > 0 ? 1.5 * c.llvmpipe : c.bound) << c.name;
}

/// The bounds. Measured on llvmpipe (the cases under its cap): per-voxel at march_step 2e-5
/// 6.0e-8, gradient with 400 lights 7.0e-6; froxel and jittered-march with 150 lights 4.86e-7
/// and 3.27e-7 (2026-12-07: the lights split over dispatches, gpu::lightDispatches; refused
/// before). The cases llvmpipe refuses have not run on a GPU
/// without a cap yet (no device in the sessions since they were written: the next GPU report
/// measures them), nor has any case run on hardware. Many lights: 7.0e-6 with the hardware
/// factor (unmeasuredOnHardware). Long marches: a step's transmittance near 1 is a float whose
/// ulp is 5.96e-8, and two devices' exp may round it to neighbours, so over a march of n steps
/// T may differ by up to n ulps, relative, where every step rounds the same way: n × 5.96e-8,
/// with n the longest ray's steps (√3 / 2e-5 = 86 603 at march_step 2e-5; 65 536 light-space
/// steps). Loose, and derived, until hardware measures them.
constexpr double kManyLights = 7.0e-6 * kUnmeasuredHardwareFactor * 1.5;
constexpr double kShortSteps = 86603 * 5.96e-8;
constexpr double kMostSteps = 65536 * 5.96e-8;

INSTANTIATE_TEST_SUITE_P(
    Methods, GpuRangeEnds,
    ::testing::Values(RangeEnd{"per_voxel_short_step",
                               {{"method", "per-voxel"}, {"march_step", 2e-5}},
                               0,
                               "'render.march_step'",
                               kShortSteps,
                               6.0e-8},
                      RangeEnd{"gradient_short_step",
                               {{"method", "gradient"}, {"march_step", 2e-5}, {"voxel_switch", 0}},
                               0,
                               "'render.march_step'",
                               kShortSteps,
                               0.0},
                      RangeEnd{"light_space_march_most_steps",
                               {{"method", "light-space-march"}, {"steps", 65536}},
                               0,
                               "'render.steps'",
                               kMostSteps,
                               0.0},
                      RangeEnd{"froxel_many_lights",
                               {{"method", "froxel"}, {"froxel_grid", {8, 6, 32}}},
                               150,
                               "the lights",
                               kManyLights,
                               4.9e-7},
                      RangeEnd{"jittered_march_many_lights",
                               {{"method", "jittered-march"}},
                               150,
                               "the lights",
                               kManyLights,
                               3.3e-7},
                      RangeEnd{
                          "gradient_many_lights",
                          {{"method", "gradient"}, {"voxel_switch", 0}},  // its samples' tracer
                          400,
                          "lights",
                          kManyLights,
                          7.0e-6}),
    [](const ::testing::TestParamInfo<RangeEnd>& i) { return std::string(i.param.name); });

}  // namespace
}  // namespace scatterlab::testing
