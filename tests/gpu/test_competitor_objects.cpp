/// The four competitors' GPU variants on scenes with objects (issue 13 with issue 12's objects):
/// light-space-march and radial-blur (gpu/light_space_march.h, gpu/radial_blur.h), jittered-march
/// and froxel (gpu/screen_march.h) against their CPU variants on a sphere's shadow in homogeneous
/// fog over a floor, for a spot, a point and a directional light. The GPU takes V_l from shadow
/// maps (render.shadow_map) and the first surface from the surface pass's raster of the
/// tessellated sphere; the CPU traces Embree rays (light-space-march: its own CPU shadow map),
/// so the images differ on shadow and silhouette edges only: the tolerances are measured.

#include <gtest/gtest.h>

#include "core/method.h"
#include "gpu_support.h"

namespace scatterlab::testing {
namespace {

/// A unit box of homogeneous fog on a floor with a sphere above it (partly in view) casting its
/// shadow into the fog and onto the floor, lit by one light of `type`, 40×30, 16³. The
/// directional light comes from in front of the camera (radial-blur needs it there).
Json objectDoc(const std::string& type, const Json& render) {
  Json doc = homogeneousBoxDoc(1.0f, 1.5f, 0.8f, Vec3(0.5f, 1.6f, 0.5f), 3.0f, 40, 30, 16);
  if (type == "spot")
    doc["lights"] = Json::array({{{"type", "spot"},
                                  {"position", {0.5, 1.6, 0.5}},
                                  {"direction", {0, -1, 0}},
                                  {"intensity", {3, 3, 3}},
                                  {"inner_deg", 25},
                                  {"outer_deg", 35}}});
  if (type == "directional")
    doc["lights"] = Json::array({{{"type", "directional"},
                                  {"direction", {0.3, -1, -0.5}},
                                  {"irradiance", {1.5, 1.5, 1.5}}}});
  doc["objects"] = Json::array(
      {{{"type", "sphere"}, {"center", {0.5, 1.25, 0.5}}, {"radius", 0.15}, {"albedo", 0.5}},
       {{"type", "box"}, {"min", {-0.5, -0.1, -0.5}}, {"max", {1.5, 0, 1.5}}, {"albedo", 0.6}}});
  doc["render"] = render;
  return doc;
}

struct Case {
  const char* light;
  Json render;
  double limit;  ///< relative L2 GPU vs CPU: measured ×1.5 (see the table below)
};

/// GoogleTest's printer gave the bytes, pointers included, and gtest_discover_tests puts the
/// printed value into ctest's names: they changed from build to build.
void PrintTo(const Case& c, std::ostream* os) {
  *os << c.light << " light, " << c.render.at("method").get<std::string>();
}

class GpuCompetitorObjects : public ::testing::TestWithParam<Case> {};

TEST_P(GpuCompetitorObjects, MatchesCpu) {
  SCATTERLAB_REQUIRE_GPU();
  const Case& c = GetParam();
  const Json doc = objectDoc(c.light, c.render);
  const RenderResult gpu = renderOn(doc, "gpu");
  const RenderResult cpu = renderOn(doc, "cpu");
  EXPECT_EQ(gpu.stats.backend, "gpu");
  const double err = relL2(gpu.image, cpu.image);
  // What the sphere does to the image (CPU, with and without it): the scale the differences
  // are measured against; the GPU must see the sphere (shadow and silhouette) as the CPU does.
  Json free = doc;
  free["objects"] = Json::array({doc["objects"][1]});
  const double sphere = relL2(renderOn(free, "cpu").image, cpu.image);
  std::printf("%s %s: gpu vs cpu %.4g, sphere's share %.4g\n", c.light, c.render.dump().c_str(),
              err, sphere);
  EXPECT_LT(err, c.limit);
  EXPECT_GT(sphere, 3.0 * err);
  EXPECT_TRUE(gpu.stats.extra["gpu_ms"].contains("shadow maps"));
  EXPECT_TRUE(gpu.stats.extra["gpu_ms"].contains("surfaces"));
  if (c.render["method"] == "light-space-march") {
    EXPECT_EQ(gpu.stats.extra["shadow_maps"], 1);  // one light
    EXPECT_EQ(cpu.stats.extra["shadow_maps"], 1);
    EXPECT_EQ(cpu.stats.extra["shadow_map_lookup"], "depth");  // VSM is GPU only
  }
  // Alpha 1 on the floor (a surface) on both backends.
  EXPECT_EQ(gpu.image.alpha()[size_t(29) * 40 + 20], 1.0f);
  EXPECT_EQ(cpu.image.alpha()[size_t(29) * 40 + 20], 1.0f);
}

const Json kLsm = {{"method", "light-space-march"},
                   {"steps", 48},
                   {"interleave", 2},
                   {"shadow_map", {{"type", "depth"}, {"resolution", 256}, {"filter", 1}}}};
const Json kBlur = {{"method", "radial-blur"},
                    {"samples", 16},
                    {"march_step", 0.05},
                    {"shadow_map", {{"resolution", 256}}}};
const Json kJitter = {{"method", "jittered-march"},
                      {"steps", 24},
                      {"shadow_map", {{"type", "depth"}, {"resolution", 256}, {"filter", 1}}}};
const Json kFroxel = {{"method", "froxel"},
                      {"froxel_grid", {40, 30, 24}},
                      {"shadow_map", {{"type", "depth"}, {"resolution", 256}, {"filter", 1}}}};

Json withKey(Json render, const char* key, const Json& value) {
  render[key] = value;
  return render;
}

// Measured on llvmpipe (Mesa 22.3.6), 2026-11-23 (relative L2 GPU vs CPU; ×1.5 below):
//                      spot      point     directional
//   light-space-march  0.2015    0.0895    1.3e-6
//   radial-blur        0.0410    0.03376   0.005013
//   jittered-march     0.1963    0.08804   0.005972
//   froxel             0.2047    0.09086   0.005974
// light-space-march's CPU map is built with the GPU's projections (shading/shadow_projection.h)
// and looked up the same way, so its medium agrees to float rounding (directional); the other
// methods' CPU variants trace exact shadow rays, so the 256² texels show on shadow edges.
// Where they differ: with the spot (light-space-march), six floor pixels on the edge of the
// sphere's shadow hold 99 % of the squared error: the surface pass's L_p finds them lit in the
// 256² map of the tessellated sphere (whose shadow is a hair smaller), Embree's exact shadow ray
// shadowed. The surface pass is shared, so every method shows it; the rest is shadow-edge
// samples in the medium where a texel disagrees with the exact ray (the directional column).
INSTANTIATE_TEST_SUITE_P(
    Methods, GpuCompetitorObjects,
    ::testing::Values(
        // directional, light-space-march: llvmpipe 1.3e-6, an NVIDIA H200 1.9e-4 (issue 23).
        Case{"spot", kLsm, 0.302}, Case{"point", kLsm, 0.134}, Case{"directional", kLsm, 2.9e-4},
        Case{"spot", kBlur, 0.0615}, Case{"point", kBlur, 0.0506},
        Case{"directional", kBlur, 0.0075}, Case{"spot", kJitter, 0.294},
        Case{"point", kJitter, 0.132}, Case{"directional", kJitter, 0.009},
        Case{"spot", kFroxel, 0.307}, Case{"point", kFroxel, 0.136},
        Case{"directional", kFroxel, 0.009},
        // Point light, measured 0.1100, 0.03587, 0.1023, 0.06938: the
        // downsampled passes read the surface of the full-resolution pixel their
        // ray passes through; froxel's transmittance maps take V from the shadow
        // maps; light-space-march with VSM on the GPU (the CPU compares depths).
        Case{"point", withKey(kJitter, "downsample", 2), 0.165},
        Case{"point", withKey(kBlur, "downsample", 2), 0.054},
        Case{"point",
             withKey(withKey(kFroxel, "light_transmittance", "map"), "transmittance_map_resolution",
                     16),
             0.154},
        Case{"point", withKey(kLsm, "shadow_map", {{"type", "vsm"}, {"resolution", 256}}), 0.104}),
    // Named by index, light and method.
    [](const ::testing::TestParamInfo<Case>& info) {
      std::string name = std::to_string(info.index) + "_" + info.param.light + "_" +
                         info.param.render.at("method").get<std::string>();
      for (char& ch : name)
        if (ch == '-') ch = '_';
      return name;
    });

}  // namespace
}  // namespace scatterlab::testing
