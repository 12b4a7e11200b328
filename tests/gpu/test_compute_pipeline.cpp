/// The compute pipeline (render.gpu_pipeline = compute, issue 23): the view march, the radiance
/// gather and the density gather against their CPU twins and against the paper's rasterised
/// passes (kept as gpu_pipeline = raster), on llvmpipe in CI and on hardware GPUs.

#include <random>

#include "core/error.h"
#include "core/stages.h"
#include "cpu/interpolation.h"
#include "cpu/per_voxel.h"
#include "cpu/ray_marcher.h"
#include "gpu/frame.h"
#include "gpu/reconstructions.h"
#include "gpu/records.h"
#include "gpu/slice_marcher.h"
#include "gpu/sphere_bins.h"
#include "gpu/tracing.h"
#include "gpu/view_march.h"
#include "gpu/volume.h"
#include "gpu/volume_tracer.h"
#include "gpu_support.h"
#include "media/procedural.h"
#include "shading/transport.h"

namespace scatterlab::testing {
namespace {

struct MarchCase {
  bool lightInside = true;
  bool factor = false;
  int spp = 1;
  float minT = 0.0f;
  bool glow = true;  ///< render.glow
  /// The camera zoomed to `axisFov` degrees down the box's z axis from (0.5, 0.5, −2) instead of
  /// oblique.
  bool alongAxis = false;
  float axisFov = 0.1f;
};

/// CPU marcher and the compute view march on the same volumes (the blob scene, an oblique
/// camera, half-voxel steps). Both take the same steps at the same points, so unlike the slice
/// marcher they agree with the light inside the medium too.
double viewMarchVsCpu(const MarchCase& c) {
  Json doc = blobSceneDoc(24, 32, 24);
  if (!c.lightInside) doc["lights"][0]["position"] = {1.25, 0.8, 0.3};
  doc["camera"]["spp"] = c.spp;
  if (c.alongAxis) doc["camera"]["fov_y_deg"] = c.axisFov;
  Scene scene = sceneFromJson(doc);
  scene.background = Vec3(0.05f, 0.1f, 0.2f);
  if (!c.alongAxis) scene.camera.position = Vec3(1.6f, 1.1f, -1.5f);
  DensityGrid density(scene.medium.bounds, scene.medium.resolution);
  scene.medium.density->build(density);
  RadianceGrid radiance(scene.medium.bounds, IVec3(20, 18, 16));
  buildPerVoxelRadiance(scene, density, 1.0f / 24, radiance, nullptr);
  MarchSettings ms;
  ms.step = 0.5f / 24;
  ms.minTransmittance = c.minT;
  ms.glow = c.glow;
  const Vec3 s = radiance.indexScale(), o = radiance.indexOffset();
  const LightFactor A(scene, {}, c.glow);
  // The CPU's plain march: S = V · A over each step (LightFactor::overStep, the glow included).
  struct Lookup {
    const DensityGrid& density;
    const RadianceGrid& radiance;
    const LightFactor* A;
    Vec3 s, o;
    bool operator()(const Vec3& u, const Ray& r, float t, float dt, float& D, Vec3& S) const {
      D = density.sampleIndex(u);
      if (D <= 0.0f) return false;
      S = radiance.sampleIndex(r.at(t) * s + o);
      if (A && S != Vec3(0.0f)) S *= A->overStep(r, t, dt);
      return true;
    }
  };
  const Image cpu = marchWith(
      scene, density, Lookup{density, radiance, c.factor ? &A : nullptr, s, o}, ms, nullptr);
  PipelineSettings ps;
  ps.march = ms;
  ps.factorLights = c.factor;
  auto integ = integrators().get("ray-marcher", "integrator").on[int(Backend::Gpu)](ps);
  gpu::GpuFrame frame(density);
  frame.radiance = gpu::uploadRadiance(radiance);
  const Image g = integ->integrate(frame, scene, nullptr);
  RenderStats st;
  integ->describe(st);
  EXPECT_EQ(st.extra["gpu_pipeline"], "compute");
  EXPECT_EQ(glGetError(), GLenum(GL_NO_ERROR));
  EXPECT_EQ(g.width(), 32);
  EXPECT_EQ(g.height(), 24);
  const double err = relL2(g, cpu);
  double alphaErr = 0.0;
  for (std::size_t i = 0; i < cpu.alpha().size(); ++i)
    alphaErr = std::max(alphaErr, double(std::abs(g.alpha()[i] - cpu.alpha()[i])));
  std::printf(
      "compute view march vs CPU (light %s, factor %d, spp %d, minT %g): relative L2 "
      "%.3g, alpha max abs %.3g\n",
      c.lightInside ? "inside" : "outside", int(c.factor), c.spp, double(c.minT), err, alphaErr);
  EXPECT_LT(alphaErr, 1e-5);
  return err;
}

// Tolerances: 1.5x the largest of what llvmpipe (Mesa 22.3.6, 2026-11-26) measured, what it
// measured with a GPU's approximate built-ins (SCATTERLAB_GPU_IMPRECISE=2 / 4, 2026-12-07) and
// what an NVIDIA H200 measured for the same arithmetic (issue 23; the compute pipeline itself
// has not run on hardware yet). The view march on uploaded volumes: llvmpipe 1.93e-6 / 1.99e-6 /
// 1.02e-6 (2026-12-07: 1.3e-7 / 2.1e-8 / 3.0e-8); imprecise 3.6e-6 / 2.3e-6 / 1.4e-6 (2 ulps),
// 6.5e-6 / 3.5e-6 / 4.6e-6 (4 ulps); on the H200 a per-pixel march with the same per-step exp
// (jittered-march) differed from the CPU by up to 3.3e-6. Since the rays are set up in the CPU's
// arithmetic (cpu_arithmetic.glsl, 2026-12-08), what the imprecise figures held of a GPU's
// normalize is gone: llvmpipe 8.2e-8 / 2.1e-8 / 2.2e-8, 4 ulps 1.5e-7 / 1.1e-7 / 2.9e-7 (the
// glow's substeps, the phase function and exp remain). Limit 5.0e-6: 1.5 × the H200's 3.3e-6,
// which was measured before and still holds its exp.
TEST(GpuViewMarch, MatchesCpuMarcherWithTheLightInsideTheMedium) {
  SCATTERLAB_REQUIRE_GPU();
  EXPECT_LT(viewMarchVsCpu({}), 5.0e-6);
}

TEST(GpuViewMarch, MatchesCpuMarcherWithFactoredLightsStrataAndEarlyExit) {
  SCATTERLAB_REQUIRE_GPU();
  EXPECT_LT(viewMarchVsCpu({.lightInside = true, .factor = true, .spp = 4, .minT = 0.05f}), 5.0e-6);
}

TEST(GpuViewMarch, MatchesCpuMarcherWithoutTheGlowsSubsteps) {
  SCATTERLAB_REQUIRE_GPU();
  // render.glow false: A at each step's midpoint only, on the GPU as on the CPU.
  EXPECT_LT(viewMarchVsCpu({.lightInside = true, .factor = true, .glow = false}), 5.0e-6);
}

// Looking down an axis of the box, zoomed: the central rays cross the unit box's depth, 48
// half-voxel steps, in exact arithmetic, so a step count by ceil alone rounded 48 on one backend
// and 49 on the other (stepCount's slack, core/stages.h). The slack moves the edge between 48
// and 49 steps to a ratio of 48.001, which no ray of this view comes near: at 0.1° the corner
// rays' ratio is 48.00005 (at 0.5° it was 48.0007 to 48.001, and a GPU's normalize 4 ulps off,
// SCATTERLAB_GPU_IMPRECISE=4, gave four corner pixels 49 steps: 5.3e-4). Any step count has such
// an edge somewhere; a generic view crosses it between pixels. Measured 2026-12-07 on llvmpipe
// (0.1°): 1.4e-7, with SCATTERLAB_GPU_IMPRECISE=2 / 4 4.8e-7 / 6.9e-7; with the GPU counting by
// ceil alone (the CPU with the slack) 4.9e-3. The limit is the view march's above.
TEST(GpuViewMarch, MatchesCpuMarcherLookingDownAnAxis) {
  SCATTERLAB_REQUIRE_GPU();
  EXPECT_LT(viewMarchVsCpu({.lightInside = true, .factor = true, .alongAxis = true}), 5.0e-6);
}

// The same view at 0.5°, where the corner rays' ratios lie within a few ulps of the slack's edge
// (48.0007 to 48.001): only a ray set up as the CPU rounds it (cpu_arithmetic.glsl: its
// direction, box entry and exit and the ratio, bit for bit) takes the CPU's count there on any
// device. Measured 2026-12-08 on llvmpipe: 7.2e-8, with SCATTERLAB_GPU_IMPRECISE=4 1.4e-7; with
// the rays in the GPU's own arithmetic and N = 4 5.3e-4 (four corner pixels at 49 steps where
// the CPU takes 48). The view march's limit.
TEST(GpuViewMarch, MatchesCpuMarcherWhereRaysLieAtTheirStepCountsEdge) {
  SCATTERLAB_REQUIRE_GPU();
  EXPECT_LT(
      viewMarchVsCpu({.lightInside = true, .factor = true, .alongAxis = true, .axisFov = 0.5f}),
      5.0e-6);
}

// A's far field is a 3D texture, not a storage buffer: at 256³ its grid (257³ vertices × 16
// bytes, 260 MiB) was above llvmpipe's 128 MiB storage block (and Mesa's Intel drivers'; GL's
// least is 16 MiB), a GpuError with no image until 2026-12-07. Here a device whose storage
// block holds less than the grid (33³ × 16 = 574 992 bytes, the limit set at 512 KiB) renders
// it, bit for bit as without the limit.
TEST(GpuViewMarch, AsFarFieldLargerThanTheDeviceStorageBlockRenders) {
  SCATTERLAB_REQUIRE_GPU();
  Json doc = testing::blobSceneDoc(32, 40, 30);
  doc["medium"]["phase"] = {{"type", "isotropic"}};
  testing::addRingOfLamps(doc, 6, 0.3, 0.5, {0.5, 0.4, 0.3});
  doc["render"] = {{"method", "gradient"}, {"voxel_switch", 0}, {"far_field", 4}};
  const Image full = testing::renderOn(doc, "gpu").image;
  struct Limit {
    Limit() { gpu::setMaxStorageBlockForTesting(std::size_t(512) << 10); }
    ~Limit() { gpu::setMaxStorageBlockForTesting(0); }
  } limit;
  ASSERT_LT(gpu::maxStorageBlock(), std::size_t(33 * 33 * 33) * 16);
  RenderResult small;
  ASSERT_NO_THROW(small = testing::renderOn(doc, "gpu"));
  EXPECT_GT(small.stats.extra.at("far_field_terms").get<long long>(), 0);
  EXPECT_EQ(relL2(small.image, full), 0.0);
}

// With factored lights the march evaluates every light's term of A at each step; on a driver
// that caps loop iterations (llvmpipe) the lights are split over dispatches
// (gpu::lightDispatches; before, 400 lamps were the loop guard's GpuError). Forced here, 4
// lights in 3 dispatches, with and without A's far field (looked up by the first part only):
// the image is one pass's to float rounding, the steps are counted once.
TEST(GpuViewMarch, FactoredLightsSplitOverDispatchesAddUpToOnePass) {
  SCATTERLAB_REQUIRE_GPU();
  Json doc = testing::blobSceneDoc(32, 40, 30);
  doc["medium"]["phase"] = {{"type", "isotropic"}};
  testing::addRingOfLamps(doc, 2, 0.3, 0.5, {0.5, 0.4, 0.3});
  for (const int far : {0, 4}) {
    doc["render"] = {{"method", "gradient"}, {"voxel_switch", 0}};
    if (far) doc["render"]["far_field"] = far;
    const RenderResult one = testing::renderSplittingLights(doc, 1);
    const RenderResult split = testing::renderSplittingLights(doc, 3);
    const auto marches = [](const RenderResult& r) {
      return r.stats.extra.at("dispatches_by_pass").value("view march", 0);
    };
    EXPECT_EQ(marches(one), 1) << far;
    EXPECT_EQ(marches(split), 3) << far;
    EXPECT_EQ(split.stats.extra.at("march_steps"), one.stats.extra.at("march_steps")) << far;
    const double e = relL2(split.image, one.image);
    std::printf("far_field %d: split over 3 dispatches vs one, relative L2 %.3g\n", far, e);
    // Measured on llvmpipe 2026-12-07: 1.29e-7 and 1.57e-7 (the parts' sums rounded in another
    // order; each term's arithmetic is the same on any device).
    EXPECT_LT(e, 2.4e-7) << far;
  }
}

// camera.spp > 1 on the GPU backend (refused until 2026-12-07, though the compute view march
// took the CPU's strata): the methods that march the view ray render k × k strata per pixel as
// the CPU does; the raster pipeline (one ray per pixel) and scene objects (one surface per
// pixel) are still refused, by name.
TEST(GpuComputePipeline, SeveralSamplesPerPixelMatchTheCpu) {
  SCATTERLAB_REQUIRE_GPU();
  Json doc = testing::blobSceneDoc(24, 32, 24);
  doc["camera"]["spp"] = 4;
  for (const char* method : {"per-voxel", "gradient", "adaptive"}) {
    doc["render"] = {{"method", method}};
    const RenderResult cpu = testing::renderOn(doc, "cpu");
    const RenderResult gpu = testing::renderOn(doc, "gpu");
    EXPECT_EQ(gpu.stats.backend, "gpu") << method;
    const double e = relL2(gpu.image, cpu.image);
    std::printf("%s, spp 4: gpu vs cpu relative L2 %.3g\n", method, e);
    // Measured 2026-12-07 on llvmpipe: 1.7e-7, 4.5e-7, 4.5e-7; with a GPU's approximate
    // built-ins simulated (SCATTERLAB_GPU_IMPRECISE=4, the CI's second run) 4.5e-7, 3.52e-5,
    // 3.52e-5. The 3.52e-5 is one pixel: the core of the glow of the point light inside the blob
    // (257.9 bright, 0.012 off, 4.8e-5 of it), where a stratum ray passes close to the lamp and
    // the factored march's A ∝ 1/d² magnifies 4-ulp errors; at spp 1 the same run gives 1.8e-6,
    // and fig3, the shaft and the glow scene at spp 4 1.2e-6 – 4.7e-6. Limit 1.5 × 3.52e-5.
    EXPECT_LT(e, 5.3e-5) << method;
  }
  doc["render"] = {{"method", "gradient"}, {"gpu_pipeline", "raster"}};
  try {
    testing::renderOn(doc, "gpu");
    FAIL() << "expected a ConfigError";
  } catch (const ConfigError& e) {
    EXPECT_NE(std::string(e.what()).find("camera.spp > 1 is not supported on the GPU backend yet "
                                         "with render.gpu_pipeline = \"raster\""),
              std::string::npos)
        << e.what();
  }
}

// Per-voxel S traces every light's shadow ray at each voxel; on a driver that caps loop
// iterations the lights are split over dispatches (gpu::lightDispatches; before, 400 lamps were
// the loop guard's GpuError). Forced here, 4 lights in 3 dispatches: `per-voxel` adds S part by
// part; `gradient` on a volume voxel_switch sends to per-voxel S (factored lights, V = S / A)
// adds FactoredSourceRadiance's sums part by part and makes V in a fourth dispatch. The image is
// one pass's to float rounding, the voxels traced are counted once.
TEST(GpuComputePipeline, PerVoxelLightsSplitOverDispatchesAddUpToOnePass) {
  SCATTERLAB_REQUIRE_GPU();
  Json doc = testing::blobSceneDoc(24, 40, 30);
  testing::addRingOfLamps(doc, 2, 0.3, 0.5, {0.5, 0.4, 0.3});
  for (const Json& render :
       {Json{{"method", "per-voxel"}}, Json{{"method", "gradient"}, {"voxel_switch", 1000}}}) {
    doc["render"] = render;
    const RenderResult one = testing::renderSplittingLights(doc, 1);
    const RenderResult split = testing::renderSplittingLights(doc, 3);
    const auto passes = [](const RenderResult& r) {
      return r.stats.extra.at("dispatches_by_pass").value("per-voxel S", 0);
    };
    const bool factored = render["method"] == "gradient";
    EXPECT_EQ(passes(one), 1) << render.dump();
    EXPECT_EQ(passes(split), factored ? 4 : 3) << render.dump();
    EXPECT_GT(one.stats.extra.at("traced_voxels").get<long long>(), 0) << render.dump();
    EXPECT_EQ(split.stats.extra.at("traced_voxels"), one.stats.extra.at("traced_voxels"));
    EXPECT_EQ(split.stats.extra.at("empty_voxels"), one.stats.extra.at("empty_voxels"));
    const double e = relL2(split.image, one.image);
    std::printf("%s: split over 3 dispatches vs one, relative L2 %.3g\n", render.dump().c_str(), e);
    // Measured on llvmpipe 2026-12-07: 9.6e-9 and 8.3e-8 (the parts' sums rounded in another
    // order; each term's arithmetic is the same on any device).
    EXPECT_LT(e, 1.3e-7) << render.dump();
  }
}

// A's far field (render.far_field): the GPU's grid of far terms (far_field.comp.glsl) and its
// lookups in the march are the CPU's arithmetic; the raster pipeline refuses the key.
TEST(GpuViewMarch, AsFarFieldMatchesTheCpus) {
  SCATTERLAB_REQUIRE_GPU();
  Json doc = testing::blobSceneDoc(32, 40, 30);
  doc["medium"]["phase"] = {{"type", "isotropic"}};
  testing::addRingOfLamps(doc, 6, 0.3, 0.5, {0.5, 0.4, 0.3});
  doc["render"] = {{"method", "gradient"}, {"voxel_switch", 0}, {"fast_march", false}};
  const Image exactGpu = testing::renderOn(doc, "gpu").image;
  doc["render"]["far_field"] = 4;
  const Image cpu = testing::renderOn(doc, "cpu").image;
  const Image gpu = testing::renderOn(doc, "gpu").image;
  const double err = relL2(gpu, cpu), change = relL2(gpu, exactGpu);
  std::printf("far field GPU vs CPU %.3g; against every light exact %.3g\n", err, change);
  // Measured on llvmpipe 2026-11-30: 6.14e-7 (the march's own CPU-GPU rounding, as without
  // the far field: 5.95e-7 on fig3 with 64 lamps); unmeasured on hardware.
  EXPECT_LT(err, unmeasuredOnHardware(6.14e-7));
  EXPECT_GT(change, 10.0 * err);  // the grid is used
  // The grid is kept with the lights: a frame that moved only the camera runs no far-field pass;
  // (the point light, a spot and the six lamps 2…7) one that moved a lamp updates the grid in place
  // (two passes over that lamp's terms: its old one out, its new one in), 16 times in a row, then
  // builds it whole; one that moved more than half the lamps builds it whole. The images follow the
  // CPU's, which updates likewise.
  Renderer r(doc, ".", "gradient", "gpu");
  const auto passes = [](const RenderResult& res, const char* name) {
    return res.stats.extra.at("dispatches_by_pass").value(name, 0);
  };
  const RenderResult first = r.render();
  EXPECT_EQ(passes(first, "far field"), 1);
  // 7 point-light terms at each vertex a step can read (SL_FAR_SKIP), at most the 33³.
  const long long built = first.stats.extra.at("far_field_terms").get<long long>();
  EXPECT_EQ(built % 7, 0);
  EXPECT_GT(built, 0);
  EXPECT_LE(built, 7 * 35937);
  r.set("camera.position=[0.6,0.5,-2]");
  doc["camera"]["position"] = {0.6, 0.5, -2};
  const RenderResult camera = r.render();
  EXPECT_EQ(passes(camera, "far field") + passes(camera, "far field update"), 0);
  EXPECT_EQ(camera.stats.extra.at("far_field_terms"), 0);
  Renderer onCpu(doc, ".", "gradient", "cpu");
  double worst = 0.0;
  for (int m = 1; m <= 17; ++m) {
    const std::string set = "lights." + std::to_string(2 + m % 6) + ".position=[" +
                            std::to_string(0.5 + 0.3 * std::cos(m)) + ",0.5," +
                            std::to_string(0.5 + 0.3 * std::sin(m)) + "]";
    r.set(set);
    onCpu.set(set);
    const RenderResult moved = r.render();
    EXPECT_EQ(passes(moved, "far field"), m <= 16 ? 0 : 1) << m;
    EXPECT_EQ(passes(moved, "far field update"), m <= 16 ? 2 : 0) << m;
    // The same vertices: 2 terms each for the lamp moved, or one per point light when built whole.
    EXPECT_EQ(moved.stats.extra.at("far_field_terms"), m <= 16 ? 2 * built / 7 : built) << m;
    worst = std::max(worst, relL2(moved.image, onCpu.render().image));
  }
  for (int l = 2; l <= 6; ++l) r.set("lights." + std::to_string(l) + ".intensity=[0.4,0.4,0.3]");
  const RenderResult many = r.render();
  EXPECT_EQ(passes(many, "far field"), 1) << many.stats.extra.at("dispatches_by_pass").dump();
  std::printf("far field updated in place, GPU vs CPU: worst %.3g\n", worst);
  // Measured on llvmpipe 2026-12-07: 8.62e-7 at worst over the 17 frames (16 updated in place,
  // on the GPU in two passes, on the CPU in one); unmeasured on hardware.
  EXPECT_LT(worst, unmeasuredOnHardware(8.62e-7));
  doc["render"]["gpu_pipeline"] = "raster";
  EXPECT_THROW(
      {
        try {
          testing::renderOn(doc, "gpu");
        } catch (const ConfigError& e) {
          EXPECT_NE(std::string(e.what()).find("built for the compute pipeline"),
                    std::string::npos);
          throw;
        }
      },
      ConfigError);
}

TEST(GpuViewMarch, MatchesCpuMarcherWithTheLightOutside) {
  SCATTERLAB_REQUIRE_GPU();
  EXPECT_LT(viewMarchVsCpu({.lightInside = false}), 5e-6);
}

// A radiance volume built on the density's grid carries the density in alpha, and the march then
// reads both in one lookup (SL_FUSED): the same image as two lookups, to rounding (the radiance
// is looked up at the density's index instead of one computed from the world point).
TEST(GpuViewMarch, OneFusedLookupPerStepEqualsTwoLookups) {
  SCATTERLAB_REQUIRE_GPU();
  Json doc = blobSceneDoc(24, 32, 24);
  const Scene scene = sceneFromJson(doc);
  DensityGrid density(scene.medium.bounds, scene.medium.resolution);
  scene.medium.density->build(density);
  const gpu::Volume d = gpu::uploadDensity(density);
  gpu::Volume r = gpu::PerVoxelGpu(1.0f / 24).build(scene, d, scene.medium.bounds,
                                                    scene.medium.resolution, nullptr, nullptr);
  ASSERT_TRUE(r.densityInAlpha);
  // The alpha is the density voxel by voxel.
  std::vector<float> rgba(std::size_t(24 * 24 * 24) * 4);
  glGetTextureImage(r.texture.id(), 0, GL_RGBA, GL_FLOAT, GLsizei(rgba.size() * sizeof(float)),
                    rgba.data());
  for (std::size_t i = 0; i < density.size(); i += 37)
    ASSERT_EQ(rgba[4 * i + 3], density.data()[i]) << i;
  MarchSettings ms;
  ms.step = 0.5f / 24;
  ms.minTransmittance = 0.0f;
  gpu::ViewMarchGpu march(ms, false, ms.step, ShadowMapSettings{});
  const Image fused = march.integrate(scene, d, r, nullptr);
  r.densityInAlpha = false;
  const Image twoLookups = march.integrate(scene, d, r, nullptr);
  const double err = relL2(fused, twoLookups);
  std::printf("fused vs two lookups per step: relative L2 %.3g\n", err);
  // Measured on llvmpipe 2026-11-26: 1.42e-6 (rounding of the index, a few ulps of u, times
  // the volume's gradient: the same on any device); ×1.5.
  EXPECT_LT(err, 2.2e-6);
}

/// Empty-space skipping (issue 34, gpu/empty_space.h): on the plume (data/scenes/fig3.json at
/// 64³, 96 × 96) the compute march's image is the plain march's bit for bit, with one fused
/// lookup per step or two, with strata and early exit; the steps it looks up and jumps over add
/// up to the plain march's.
TEST(GpuViewMarch, SkippingEmptyBlocksChangesNoBit) {
  SCATTERLAB_REQUIRE_GPU();
  initialize();
  Scene scene = loadScene(std::string(SCATTERLAB_SOURCE_DIR) + "/data/scenes/fig3.json",
                          {"medium.resolution=64", "camera.width=96", "camera.height=96"});
  const DensityGrid density = buildDensityVolume(scene);
  const gpu::Volume d = gpu::uploadDensity(density);
  const float voxel = scene.medium.voxelSize();
  gpu::Volume r = gpu::PerVoxelGpu(voxel).build(scene, d, scene.medium.bounds,
                                                scene.medium.resolution, nullptr, nullptr);
  ASSERT_TRUE(r.densityInAlpha);
  struct Case {
    bool fused;
    int spp;
    float minT;
  };
  for (const Case c : {Case{true, 1, 1e-6f}, Case{false, 4, 0.05f}}) {
    r.densityInAlpha = c.fused;
    scene.camera.spp = c.spp;
    MarchSettings ms;
    ms.step = voxel;
    ms.minTransmittance = c.minT;
    gpu::ViewMarchGpu march(ms, false, voxel, ShadowMapSettings{});
    gpu::Buffer skipCounts, plainCounts;
    const Image skip = march.integrate(scene, d, r, nullptr, nullptr, &skipCounts);
    march.skipEmptySpace(false);
    const Image plain = march.integrate(scene, d, r, nullptr, nullptr, &plainCounts);
    EXPECT_TRUE(skip.pixels() == plain.pixels()) << "fused " << c.fused;
    EXPECT_TRUE(skip.alpha() == plain.alpha()) << "fused " << c.fused;
    gpu::GpuMarchCounters s, p;
    skipCounts.read(&s, sizeof s);
    plainCounts.read(&p, sizeof p);
    const long long looked = gpu::GpuMarchCounters::join(s.looked);
    const long long skipped = gpu::GpuMarchCounters::join(s.skipped);
    EXPECT_EQ(gpu::GpuMarchCounters::join(p.skipped), 0);
    EXPECT_EQ(looked + skipped, gpu::GpuMarchCounters::join(p.looked)) << "fused " << c.fused;
    std::printf("fig3 64^3 (fused %d, spp %d, minT %g): %lld steps looked up, %lld skipped\n",
                int(c.fused), c.spp, double(c.minT), looked, skipped);
  }
}

/// A's far field on the GPU computes only the vertices a step can read (far_field.comp.glsl,
/// SL_FAR_SKIP, from the empty-space grid): on the plume at 64³ (most blocks empty) with 6 lamps,
/// the march's image with it equals, bit for bit, the image over a grid with every vertex
/// computed (skipping off), with one fused lookup per step or two.
TEST(GpuViewMarch, AsFarFieldOnlyWhereAStepCanReadItChangesNoBit) {
  SCATTERLAB_REQUIRE_GPU();
  initialize();
  Scene scene = loadScene(std::string(SCATTERLAB_SOURCE_DIR) + "/data/scenes/fig3.json",
                          {"medium.resolution=64", "camera.width=96", "camera.height=96"});
  const Box& box = scene.medium.bounds;
  for (int i = 0; i < 6; ++i) {  // a ring of lamps around the box's centre, inside it
    Light light;
    const float phi = 1.0471976f * float(i);
    light.position = box.center() + 0.35f * box.extent() * Vec3(std::cos(phi), 0.2f, std::sin(phi));
    light.intensity = Vec3(0.5f, 0.4f, 0.3f);
    scene.lights.push_back(light);
  }
  const DensityGrid density = buildDensityVolume(scene);
  const float voxel = scene.medium.voxelSize();
  MarchSettings ms;
  ms.step = voxel;
  ms.farField = 4.0f;
  for (const bool fused : {true, false}) {
    // Each march its own density volume: the grid is kept with the volume's lights.
    Image images[2];
    for (const bool skip : {true, false}) {
      const gpu::Volume d = gpu::uploadDensity(density);
      gpu::Volume r = gpu::PerVoxelGpu(voxel).build(scene, d, scene.medium.bounds,
                                                    scene.medium.resolution, nullptr, nullptr);
      r.densityInAlpha = fused;
      gpu::ViewMarchGpu march(ms, true, voxel, ShadowMapSettings{});
      march.skipEmptySpace(skip);
      images[skip ? 0 : 1] = march.integrate(scene, d, r, nullptr);
    }
    EXPECT_TRUE(images[0].pixels() == images[1].pixels()) << "fused " << fused;
    EXPECT_GT(compareImages(images[0], Image(96, 96)).relL2, 0.5);  // not black
  }
}

/// The issue's target: rendered by the gradient method at its own resolution (128³; 96 × 96
/// pixels), the plume's GPU march reports at least half of its steps skipped (measured on
/// llvmpipe: 56 % at 256 × 256), and the tracer at least one invocation per sample and light;
/// the CPU march counts the same steps.
TEST(GpuViewMarch, ThePlumeSkipsAtLeastHalfItsSteps) {
  SCATTERLAB_REQUIRE_GPU();
  initialize();
  const Scene scene = loadScene(std::string(SCATTERLAB_SOURCE_DIR) + "/data/scenes/fig3.json",
                                {"camera.width=96", "camera.height=96"});
  const RenderResult res = createMethod(scene, "gradient", "gpu")->render(scene, nullptr);
  const Json& x = res.stats.extra;
  const long long looked = x.at("march_steps").get<long long>();
  const long long skipped = x.at("march_steps_skipped").get<long long>();
  std::printf("fig3 gradient on the GPU: %lld march steps looked up, %lld skipped (%.1f %%)\n",
              looked, skipped, 100.0 * double(skipped) / double(looked + skipped));
  EXPECT_GE(2 * skipped, looked + skipped);
  EXPECT_GE(x.at("tracer_invocations").get<long long>(),
            res.stats.samples.value() * (long long)scene.lights.size());
  // The CPU march walks the same blocks with the same steps: the same counts (measured equal).
  const RenderResult cpu = createMethod(scene, "gradient", "cpu")->render(scene, nullptr);
  EXPECT_EQ(cpu.stats.extra.at("march_steps").get<long long>(), looked);
  EXPECT_EQ(cpu.stats.extra.at("march_steps_skipped").get<long long>(), skipped);
}

std::vector<RadianceSample> randomSamples(int n, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<float> u(0.0f, 1.0f), s(-2.0f, 2.0f);
  std::vector<RadianceSample> out(static_cast<std::size_t>(n));
  for (RadianceSample& r : out) {
    // Some spheres reach past the box (bins at the border) and some are tiny (one bin).
    r.position = Vec3(u(rng), u(rng), u(rng)) * 1.2f - 0.1f;
    r.radius = u(rng) < 0.2f ? 0.02f : 0.1f + 0.3f * u(rng);
    r.S = Vec3(1.0f + u(rng), 0.5f + u(rng), 2.0f * u(rng) + 0.2f);
    for (Vec3& g : r.dS) g = Vec3(s(rng), s(rng), s(rng));
  }
  return out;
}

/// The radiance volume of the gradient reconstruction under `pipeline`.
RadianceGrid reconstructOn(GpuPipeline pipeline, bool occlusion, const Scene& scene,
                           const DensityGrid& density, const std::vector<RadianceSample>& samples,
                           IVec3 dims, long long* uncovered) {
  PipelineSettings ps;
  ps.gpuPipeline = pipeline;
  ps.occlusionWeights = occlusion;
  ps.boundedTaylor = true;
  auto rec = reconstructions().get("gradient", "reconstruction").on[int(Backend::Gpu)](ps);
  gpu::GpuFrame frame(density);
  const ReconstructionStats st = rec->reconstruct(frame, scene, samples, dims, nullptr);
  *uncovered = st.uncovered;
  return gpu::readRadiance(frame.radiance);
}

/// The gather sums each voxel's samples in the order the raster splat blends them, with the
/// same per-sample arithmetic: the volumes agree to rounding (fma contraction may differ) where
/// a sphere covers the voxel. (Occupied voxels no sphere covers: the compute pipeline gives them
/// the nearest sample's S, as the CPU; the raster splat leaves them 0. GpuGradientSplat.*.)
void gatherVsSplat(bool occlusion) {
  const Scene scene = sceneFromJson(blobSceneDoc(20, 8, 6));
  const IVec3 dims(21, 18, 17);  // not multiples of the bin size: partial bins at the far faces
  DensityGrid density(scene.medium.bounds, dims);
  scene.medium.density->build(density);
  const std::vector<RadianceSample> samples = randomSamples(60, 5);
  long long ug = 0, ur = 0;
  const RadianceGrid g =
      reconstructOn(GpuPipeline::Compute, occlusion, scene, density, samples, dims, &ug);
  const RadianceGrid r =
      reconstructOn(GpuPipeline::Raster, occlusion, scene, density, samples, dims, &ur);
  EXPECT_EQ(ug, ur);
  double num = 0, den = 0, maxRel = 0;
  for (std::size_t i = 0; i < g.size(); ++i) {
    const int x = int(i % std::size_t(dims.x)), y = int(i / dims.x % dims.y),
              z = int(i / dims.x / dims.y);
    if (interpolateAt(Interpolation::Gradient, g.cellCenter(x, y, z), samples).covering == 0)
      continue;
    const Vec3 d = g.data()[i] - r.data()[i];
    num += glm::dot(d, d);
    den += glm::dot(r.data()[i], r.data()[i]);
    for (int c = 0; c < 3; ++c)
      maxRel = std::max(maxRel, double(std::abs(d[c])) / (std::abs(r.data()[i][c]) + 1e-3));
  }
  const double err = std::sqrt(num / den);
  std::printf("radiance gather vs raster splat (occlusion %d): relative L2 %.3g, max rel %.3g\n",
              int(occlusion), err, maxRel);
  EXPECT_GT(den, 0.0);
  // Measured 0 and 0 on llvmpipe (bit-identical). The bounds leave room for a hardware
  // compiler contracting the fragment's and the compute shader's Taylor sums into fma
  // differently (a few ulps per voxel), nothing more.
  EXPECT_LT(err, 1e-6);
  EXPECT_LT(maxRel, 1e-5);
}

TEST(GpuRadianceGather, EqualsTheRasterSplat) {
  SCATTERLAB_REQUIRE_GPU();
  gatherVsSplat(false);
}

TEST(GpuRadianceGather, EqualsTheRasterSplatWithOcclusionWeights) {
  SCATTERLAB_REQUIRE_GPU();
  gatherVsSplat(true);
}

/// A voxel centre exactly on a sample's valid sphere is outside it (Eq. 4's ‖x − x_j‖ < R_j is
/// strict) on the GPU as on the CPU. The samples sit on voxel centres of a 32³ grid with radii
/// of 3 and 5 voxels, so that 30 voxel centres lie exactly on each sphere ((3, 0, 0), (2, 2, 1)
/// and their permutations and signs; (5, 0, 0), (4, 3, 0), ...): every coordinate, difference
/// and square is exact in float. W is R/‖x − x_j‖ ≈ 1 there, not 0, so a centre let in moves
/// the voxel by a large fraction. The gathers decide by d² < R², as the CPU does, never by a
/// square root: a GPU's sqrt a few ulps off (NVIDIA's; CI's imprecise run simulates it with
/// SCATTERLAB_GPU_IMPRECISE=4) moved half of those centres inside when the gather compared
/// length(d) with R. That moved the shipped chimney's `adaptive` image by 2.4e-4 relative L2
/// (measured 2026-12-08, 160 × 120; 2.8e-6 with the squared test). This test failed under the
/// imprecise run with the old test: 4.2e-2 relative L2 over the covered voxels (compute; the
/// raster splat 4.1e-2), at N = 4 and at N = 2.
void gatherOnSpheres(GpuPipeline pipeline) {
  const Scene scene =
      sceneFromJson(homogeneousBoxDoc(1.0f, 1.2f, 0.6f, Vec3(0.5f, 1.3f, 0.6f), 1.0f, 8, 6, 32));
  const IVec3 dims(32);
  const DensityGrid density = buildDensityVolume(scene);
  std::mt19937 rng(17);
  std::uniform_real_distribution<float> u(0.0f, 1.0f), g(-4.0f, 4.0f);
  std::vector<RadianceSample> samples;
  for (int n = 0; n < 24; ++n) {
    RadianceSample r;
    const IVec3 c(6 + int(u(rng) * 20), 6 + int(u(rng) * 20), 6 + int(u(rng) * 20));
    r.position = (Vec3(c) + 0.5f) / 32.0f;
    r.radius = (n % 2 ? 5.0f : 3.0f) / 32.0f;
    r.S = Vec3(1.0f + u(rng), 0.5f + u(rng), 0.2f + 2.0f * u(rng));
    for (Vec3& d : r.dS) d = Vec3(g(rng), g(rng), g(rng));
    samples.push_back(r);
  }
  RadianceGrid cpu(scene.medium.bounds, dims);
  interpolateSamples(Interpolation::Gradient, density, samples, cpu);
  PipelineSettings ps;
  ps.gpuPipeline = pipeline;
  auto rec = reconstructions().get("gradient", "reconstruction").on[int(Backend::Gpu)](ps);
  gpu::GpuFrame frame(density);
  rec->reconstruct(frame, scene, samples, dims, nullptr);
  const RadianceGrid gpu = gpu::readRadiance(frame.radiance);
  double num = 0, den = 0;
  long long onSphere = 0;
  for (int k = 0; k < dims.z; ++k)
    for (int j = 0; j < dims.y; ++j)
      for (int i = 0; i < dims.x; ++i) {
        const Vec3 x = cpu.cellCenter(i, j, k);
        if (interpolateAt(Interpolation::Gradient, x, samples).covering == 0) continue;
        for (const RadianceSample& s : samples) {
          const Vec3 d = x - s.position;
          onSphere += glm::dot(d, d) == s.radius * s.radius;
        }
        const Vec3 e = gpu.at(i, j, k) - cpu.at(i, j, k);
        num += glm::dot(e, e);
        den += glm::dot(cpu.at(i, j, k), cpu.at(i, j, k));
      }
  const double err = std::sqrt(num / den);
  std::printf("gather on spheres (%s): %lld centres on a sphere, CPU = GPU relative L2 %.3g\n",
              pipeline == GpuPipeline::Compute ? "compute" : "raster", onSphere, err);
  // (sample, covered centre) pairs at distance exactly R: 291 with libstdc++'s distributions
  // (only the centres some other sphere covers count; uncovered voxels take the nearest S).
  EXPECT_GT(onSphere, 200);
  // Measured 2026-12-08 on llvmpipe: 7.2e-8 (compute and raster); with
  // SCATTERLAB_GPU_IMPRECISE=4 and 2: 8.0e-8 (the old length(d) < R test: 4.2e-2). Not yet on
  // hardware, whose division and fused Taylor sums the simulation does not reach: the hardware
  // factor on the largest (3.4e-7, five orders below what one centre let in costs).
  EXPECT_LT(err, unmeasuredOnHardware(8.0e-8));
}

TEST(GpuRadianceGather, AVoxelCentreOnASphereIsOutsideItAsOnTheCpu) {
  SCATTERLAB_REQUIRE_GPU();
  gatherOnSpheres(GpuPipeline::Compute);
}

TEST(GpuRadianceSplat, AVoxelCentreOnASphereIsOutsideItAsOnTheCpu) {
  SCATTERLAB_REQUIRE_GPU();
  gatherOnSpheres(GpuPipeline::Raster);
}

TEST(GpuDensityGather, EqualsTheCpuBuildAndTheRasterSplat) {
  SCATTERLAB_REQUIRE_GPU();
  const Scene scene = sceneFromJson(blobSceneDoc(24, 8, 6));
  const auto& gauss = dynamic_cast<const GaussianDensity&>(*scene.medium.density);
  const IVec3 dims(26, 20, 17);
  DensityGrid cpu(scene.medium.bounds, dims);
  gauss.build(cpu);
  const DensityGrid gather = gpu::readDensity(
      gpu::splatGaussians(gauss.blobs(), scene.medium.bounds, dims, nullptr, GpuPipeline::Compute));
  const DensityGrid raster = gpu::readDensity(
      gpu::splatGaussians(gauss.blobs(), scene.medium.bounds, dims, nullptr, GpuPipeline::Raster));
  float maxD = 0, errCpu = 0, errRaster = 0;
  for (float d : cpu.data()) maxD = std::max(maxD, d);
  for (std::size_t i = 0; i < cpu.size(); ++i) {
    errCpu = std::max(errCpu, std::abs(gather.data()[i] - cpu.data()[i]));
    errRaster = std::max(errRaster, std::abs(gather.data()[i] - raster.data()[i]));
  }
  std::printf("density gather: max abs vs CPU %.3g, vs raster %.3g (max density %.3g)\n",
              double(errCpu), double(errRaster), double(maxD));
  EXPECT_GT(maxD, 0.5f);
  // vs CPU: llvmpipe 1.79e-7 at max D 1.13 (the exp), 4.8e-7 / 6.0e-7 with
  // SCATTERLAB_GPU_IMPRECISE=2 / 4; the H200's raster splat of a .sog's Gaussians 2.98e-7 at
  // max D 0.96: 1.5x of the largest, 9e-7. vs raster: 0 on llvmpipe (the same sums in the same
  // order); the bound is the same.
  EXPECT_LT(errCpu, 9e-7f);
  EXPECT_LT(errRaster, 9e-7f);
}

TEST(GpuSphereBins, ListsEverySphereThatReachesABinInAscendingOrder) {
  SCATTERLAB_REQUIRE_GPU();
  const Box box{Vec3(0.0f), Vec3(1.0f)};
  const IVec3 dims(20, 9, 17);
  const std::vector<glm::vec4> spheres = {{0.5f, 0.5f, 0.5f, 0.05f},  // one or two bins
                                          {0.0f, 0.0f, 0.0f, 2.0f},   // every bin
                                          {5.0f, 0.5f, 0.5f, 1.0f},   // outside: none
                                          {0.9f, 0.1f, 0.9f, 0.0f}};  // zero radius: none
  const gpu::SphereBins b = gpu::binSpheres(spheres, box, dims, "test");
  EXPECT_EQ(b.bins, IVec3(3, 2, 3));
  ASSERT_EQ(b.offsets.size(), 3u * 2u * 3u + 1u);
  for (std::size_t bin = 0; bin + 1 < b.offsets.size(); ++bin) {
    std::vector<GLuint> list(b.items.begin() + b.offsets[bin],
                             b.items.begin() + b.offsets[bin + 1]);
    EXPECT_TRUE(std::is_sorted(list.begin(), list.end()));
    EXPECT_TRUE(std::count(list.begin(), list.end(), 1u) == 1) << "bin " << bin;
    EXPECT_EQ(std::count(list.begin(), list.end(), 2u), 0);
    EXPECT_EQ(std::count(list.begin(), list.end(), 3u), 0);
  }
  // Bin (1, 0, 1) holds voxels 8..15 × 0..7 × 8..15 (x centres 0.425..0.775, y 0.056..0.833,
  // z 0.5..0.912): sphere 0's centre voxel (10, 4, 8) is in it; bin (2, 1, 2) is far from it.
  const std::size_t centre = (1 * 2 + 0) * 3 + 1, far = (2 * 2 + 1) * 3 + 2;
  EXPECT_EQ(
      std::count(b.items.begin() + b.offsets[centre], b.items.begin() + b.offsets[centre + 1], 0u),
      1);
  EXPECT_EQ(std::count(b.items.begin() + b.offsets[far], b.items.begin() + b.offsets[far + 1], 0u),
            0);
}

TEST(GpuSphereBins, ListsLargerThanTheDeviceAllowsAreAGpuErrorBeforeAnyWork) {
  SCATTERLAB_REQUIRE_GPU();
  // 200 000 spheres covering all 64³ bins of a 512³ grid: 5.2e10 entries, 210 GB.
  const std::vector<glm::vec4> spheres(200000, glm::vec4(0.5f, 0.5f, 0.5f, 2.0f));
  try {
    gpu::binSpheres(spheres, Box{Vec3(0.0f), Vec3(1.0f)}, IVec3(512), "radiance gather");
    FAIL() << "no error";
  } catch (const GpuError& e) {
    const std::string m = e.what();
    EXPECT_NE(m.find("radiance gather"), std::string::npos) << m;
    EXPECT_NE(m.find("MiB"), std::string::npos) << m;
    EXPECT_NE(m.find("GL_MAX_SHADER_STORAGE_BLOCK_SIZE"), std::string::npos) << m;
  }
}

// A volume larger than the device allows is a GpuError naming the volume and the bytes asked,
// before anything is allocated (not a GL error later, a driver crash or a black image).
TEST(GpuComputePipeline, AVolumeLargerThanTheDeviceAllowsIsAGpuError) {
  SCATTERLAB_REQUIRE_GPU();
  GLint max3d = 0;
  glGetIntegerv(GL_MAX_3D_TEXTURE_SIZE, &max3d);
  ASSERT_GT(max3d, 0);
  const auto expectDeviceLimit = [&](const std::string& m) {
    EXPECT_NE(m.find("source radiance"), std::string::npos) << m;
    EXPECT_NE(m.find(std::to_string(max3d + 1) + " x 2 x 2"), std::string::npos) << m;
    EXPECT_NE(m.find("MiB"), std::string::npos) << m;
    EXPECT_NE(m.find("GL_MAX_3D_TEXTURE_SIZE"), std::string::npos) << m;
  };
  // Resolution keys allow 4096 per axis (core/params.h). Where the device allows less
  // (llvmpipe: 2048), a render asking for more fails with the device's limit; where it allows
  // more (NVIDIA: 16384) the key's own limit is the first error, and the device's is checked
  // where the volume is made.
  constexpr int kKeyLimit = 4096;
  if (max3d + 1 <= kKeyLimit) {
    initialize();
    Json doc = blobSceneDoc(16, 16, 12);
    doc["render"] = {{"method", "per-voxel"}, {"radiance_resolution", {max3d + 1, 2, 2}}};
    const Scene s = parseScene(doc, ".");
    try {
      createMethod(s, "", "gpu")->render(s, nullptr);
      FAIL() << "no error";
    } catch (const GpuError& e) {
      expectDeviceLimit(e.what());
    }
  } else {
    initialize();
    Json doc = blobSceneDoc(16, 16, 12);
    doc["render"] = {{"method", "per-voxel"}, {"radiance_resolution", {kKeyLimit + 1, 2, 2}}};
    EXPECT_THROW(
        {
          const Scene s = parseScene(doc, ".");
          createMethod(s, "", "gpu")->render(s, nullptr);
        },
        ConfigError);
  }
  try {
    (void)gpu::makeRadianceVolume(Box{Vec3(0.0f), Vec3(1.0f)}, IVec3(max3d + 1, 2, 2),
                                  "source radiance");
    FAIL() << "no error";
  } catch (const GpuError& e) {
    expectDeviceLimit(e.what());
  }
  EXPECT_EQ(glGetError(), GLenum(GL_NO_ERROR));
}

/// A method on the CPU and on the GPU under both pipelines, end to end through createMethod.
void endToEnd(const char* method, double computeTol, double rasterTol) {
  initialize();
  Json doc = blobSceneDoc(20, 32, 24);
  doc["render"]["method"] = method;
  doc["render"]["march_step"] = 0.5 / 20;
  if (std::string(method) != "per-voxel")
    doc["render"]["sampler"] = {{"type", "jittered"}, {"count", 96}};
  if (std::string(method) == "adaptive") {
    doc["render"]["levels"] = {4, 8};
    doc["render"]["voxel_switch"] = 0;  // dynamic sampling itself, not the whole-scene fallback
  }
  const Scene scene = parseScene(doc, ".");
  const RenderResult cpu = createMethod(scene, "", "cpu")->render(scene, nullptr);
  const RenderResult compute = createMethod(scene, "", "gpu")->render(scene, nullptr);
  Json rdoc = doc;
  rdoc["render"]["gpu_pipeline"] = "raster";
  const Scene rscene = parseScene(rdoc, ".");
  const RenderResult raster = createMethod(rscene, "", "gpu")->render(rscene, nullptr);
  EXPECT_EQ(compute.stats.extra["gpu_pipeline"], "compute");
  EXPECT_EQ(raster.stats.extra["gpu_pipeline"], "raster");
  const double ec = relL2(compute.image, cpu.image), er = relL2(raster.image, cpu.image);
  std::printf("%s vs CPU: compute %.3g, raster %.3g (relative L2)\n", method, ec, er);
  EXPECT_LT(ec, computeTol);
  EXPECT_LT(er, rasterTol);
  // The CPU names the GPU-only key as unused.
  const RenderResult cpuR = createMethod(rscene, "", "cpu")->render(rscene, nullptr);
  EXPECT_EQ(cpuR.stats.extra["unused_keys"], Json::array({"render.gpu_pipeline"}));
}

// The issue's target: compute ≡ CPU within 1e-4 relative L2 on llvmpipe, 1e-3 on hardware.
// Measured (gradient / per-voxel / adaptive with levels 4, 8), relative L2 against the CPU:
//   llvmpipe 2026-11-26: compute 1.22e-6 / 1.43e-6 / 1.2e-6, raster 9.56e-7 / 8.33e-7 / 1.01e-6
//   (2026-11-28, the compute gather filling uncovered voxels from the nearest sample as the CPU:
//   compute 1.05e-7 / 9.88e-8 / 1.34e-7);
//   NVIDIA H200 (driver 580.159.04) 2026-11-27: compute 1.9e-6 / 7.21e-7 / 1.94e-6, raster
//   1.44e-4 / 5.41e-4 / 1.38e-4 (the raster pipeline's rasterised slices and blending: the
//   compute pipeline is the one that matches on hardware).
// Limits 1.5x the largest over both devices, per pipeline.
TEST(GpuComputePipeline, GradientEndToEndMatchesCpu) {
  SCATTERLAB_REQUIRE_GPU();
  endToEnd("gradient", 2.9e-6, 2.2e-4);
}

TEST(GpuComputePipeline, PerVoxelEndToEndMatchesCpu) {
  SCATTERLAB_REQUIRE_GPU();
  endToEnd("per-voxel", 2.2e-6, 8.1e-4);
}

TEST(GpuComputePipeline, AdaptiveEndToEndMatchesCpu) {
  SCATTERLAB_REQUIRE_GPU();
  // With SCATTERLAB_GPU_IMPRECISE=2 or 4 (2026-12-07) both pipelines gave 1.75e-5, the same
  // samples per level: not a split, as was thought, but the gathers' sphere test (length(d) < R,
  // voxel centres on level samples' spheres; d² < R² since 2026-12-08). Re-measured then:
  // compute 2.6e-7 / 4.0e-7, raster 2.6e-7 / 2.7e-7 (N = 2 / 4); llvmpipe 8.9e-8 / 4.1e-7. The
  // limits stay 1.5x the H200's figures above (measured with the old test: not re-measured).
  endToEnd("adaptive", 2.9e-6, 2.1e-4);
}

// Where no spot cone reaches (LitReach, shading/transport.h): the tracer leaves samples no cone
// reaches untraced, the gather leaves voxels 0, the per-voxel fallback skips them, as the CPU
// does. A box of fog under a narrow spot; gradient, adaptive and adaptive's whole-scene
// fallback (per-voxel V) against the CPU.
TEST(GpuComputePipeline, WhereNoConeReachesTheGpuSkipsAsTheCpu) {
  SCATTERLAB_REQUIRE_GPU();
  initialize();
  Json doc = homogeneousBoxDoc(1.0f, 1.5f, 0.8f, Vec3(0), 1.0f, 40, 30, 24);
  doc["lights"] = Json::parse(R"([{"type": "spot", "position": [0.45, 1.4, 0.55],
      "direction": [0.1, -1, 0], "intensity": [3, 2.5, 2], "inner_deg": 6, "outer_deg": 9}])");
  doc["camera"]["position"] = {0.5, 0.6, -1.6};
  for (const Json& r : {Json{{"method", "gradient"},
                             {"sampler", {{"type", "jittered"}, {"count", 200}}},
                             {"voxel_switch", 0}},
                        Json{{"method", "adaptive"}, {"voxel_switch", 0}, {"levels", {4, 8}}},
                        Json{{"method", "adaptive"}, {"voxel_switch", 1000}}}) {
    doc["render"] = r;
    const Scene scene = parseScene(doc, ".");
    const RenderResult cpu = createMethod(scene, "", "cpu")->render(scene, nullptr);
    const RenderResult gpu = createMethod(scene, "", "gpu")->render(scene, nullptr);
    const double e = relL2(gpu.image, cpu.image);
    std::printf("%s vs CPU: %.3g (relative L2)\n", r.dump().c_str(), e);
    // Measured on llvmpipe 2026-11-28: 2.53e-6 / 2.51e-6 / 2.49e-6 (the spot's cone edge: its
    // smoothstep rounds differently on the two); 2026-12-07 8.0e-7 / 8.1e-7 / 7.8e-7, with
    // SCATTERLAB_GPU_IMPRECISE=2 6.4e-6 each, =4 1.19e-5 each. Since the cone at a sample, and
    // at a march step in its transition, is the CPU's (cpu_arithmetic.glsl, 2026-12-08):
    // 1.1e-7 / 1.3e-7 / 1.1e-7, N = 2 1.5e-7 / 1.5e-7 / 1.4e-7, N = 4 1.6e-7 / 2.3e-7 /
    // 1.7e-7, N = 8 2.7e-7 / 3.9e-7 / 2.7e-7. Not yet measured on hardware: the hardware factor
    // on llvmpipe's largest (unmeasuredOnHardware: 5.5e-7, above N = 8's), and for adaptive the
    // flipped-decision bound where its samples per level differ from the CPU's.
    EXPECT_LT(e, decisionBound(gpu.stats.extra.value("samples_per_level", Json()),
                               cpu.stats.extra.value("samples_per_level", Json()),
                               unmeasuredOnHardware(1.3e-7)))
        << r.dump();
    if (r["voxel_switch"] == 1000) {
      // The voxels traced: those the cone reaches; the cone test's trigonometry may differ by
      // an ulp between devices, so a voxel at its margin (where A is 0) may go either way.
      const auto c = cpu.stats.extra["traced_voxels"].get<long long>();
      const auto g = gpu.stats.extra["traced_voxels"].get<long long>();
      EXPECT_LT(c, 24 * 24 * 24 / 2);
      EXPECT_NEAR(double(g), double(c), 0.01 * double(c));
    }
  }
}

TEST(GpuComputePipeline, SlicingUnderTheComputePipelineIsReportedUnused) {
  SCATTERLAB_REQUIRE_GPU();
  initialize();
  Json doc = blobSceneDoc(16, 16, 12);
  doc["render"]["method"] = "per-voxel";
  doc["render"]["slicing"] = "view-planes";
  const Scene s = parseScene(doc, ".");
  const RenderResult r = createMethod(s, "", "gpu")->render(s, nullptr);
  EXPECT_EQ(r.stats.extra["gpu_pipeline"], "compute");
  EXPECT_EQ(r.stats.extra["unused_keys"], Json::array({"render.slicing"}));
}

// Issue 33: no sampler reads the density back. gaussian-centres reads nothing; the cell samplers
// (jittered, grid: they skip empty cells) count the occupancy on the GPU (pass "cell occupancy",
// 4 bytes read per grid tried), and their samples are the CPU sampler's. Every grid the search
// may try is counted ahead in one pass: with 16 voxels along the longest axis, all of them
// (the bisection's 4 steps) in one, and the chosen grid's cells read from its bits without
// another (before: a pass and a wait per grid tried, then one more for the chosen one).
TEST(GpuComputePipeline, NoSamplerReadsTheDensityBack) {
  SCATTERLAB_REQUIRE_GPU();
  initialize();
  Json doc = blobSceneDoc(16, 16, 12);
  // The samplers themselves (voxel_switch 0: not the whole-scene fallback, whose occupancy
  // count is a pass of its own).
  doc["render"] = {
      {"method", "gradient"}, {"sampler", {{"type", "gaussian-centres"}}}, {"voxel_switch", 0}};
  const Scene centres = parseScene(doc, ".");
  const RenderResult a = createMethod(centres, "", "gpu")->render(centres, nullptr);
  EXPECT_FALSE(a.stats.extra["gpu_ms"].contains("density read-back")) << a.stats.extra["gpu_ms"];
  EXPECT_EQ(*a.stats.samples, 4);
  for (const char* type : {"jittered", "grid"}) {
    doc["render"]["sampler"] = {{"type", type}, {"count", 32}};
    const Scene s = parseScene(doc, ".");
    const RenderResult g = createMethod(s, "", "gpu")->render(s, nullptr);
    const RenderResult c = createMethod(s, "", "cpu")->render(s, nullptr);
    EXPECT_FALSE(g.stats.extra["gpu_ms"].contains("density read-back")) << g.stats.extra["gpu_ms"];
    EXPECT_TRUE(g.stats.extra["gpu_ms"].contains("cell occupancy")) << g.stats.extra["gpu_ms"];
    EXPECT_EQ(g.stats.extra["dispatches_by_pass"]["cell occupancy"], 1) << type;
    ASSERT_EQ(g.samples.size(), c.samples.size()) << type;
    for (std::size_t i = 0; i < c.samples.size(); ++i) {
      EXPECT_EQ(g.samples[i].position, c.samples[i].position) << type << " sample " << i;
      EXPECT_EQ(g.samples[i].radius, c.samples[i].radius) << type << " sample " << i;
    }
  }
}

// The GPU's occupancy is the CPU's, cell for cell: a density with empty and occupied voxels
// (zeros, tiny positives, negatives), grids that divide its dims and grids that do not.
TEST(GpuComputePipeline, CellOccupancyEqualsTheCpus) {
  SCATTERLAB_REQUIRE_GPU();
  DensityGrid d(Box{Vec3(-1.0f, 0.0f, 2.0f), Vec3(2.0f, 1.5f, 3.0f)}, IVec3(23, 17, 9));
  std::uint32_t h = 12345u;
  for (float& v : d.data()) {
    h = h * 1664525u + 1013904223u;
    const std::uint32_t r = h >> 24;
    v = r < 150 ? 0.0f : r < 160 ? 1e-30f : r < 170 ? -0.5f : float(r) / 255.0f;
  }
  const std::vector<IVec3> grids = {IVec3(1), IVec3(4, 3, 2), IVec3(23, 17, 9), IVec3(7, 11, 5),
                                    IVec3(46, 5, 13)};
  // All counted in one call and one pass, then one more grid alone (its bits after theirs), then
  // every grid's list from the bits kept.
  gpu::GpuFrame frame(d);
  const long long dispatches0 = gpu::passCounts().dispatches;
  const std::vector<long long> counts = frame.countOccupiedCells(grids);
  EXPECT_EQ(gpu::passCounts().dispatches - dispatches0, 1);
  const IVec3 alone(64, 1, 3);
  EXPECT_EQ(frame.countOccupiedCells(std::span(&alone, 1)),
            std::vector<long long>{(long long)occupiedCells(d, alone).size()});
  const long long dispatches1 = gpu::passCounts().dispatches;
  for (std::size_t g = 0; g <= grids.size(); ++g) {
    const IVec3 dims = g < grids.size() ? grids[g] : alone;
    const std::vector<int> cpu = occupiedCells(d, dims);
    if (g < grids.size()) {
      EXPECT_EQ(counts[g], (long long)cpu.size());
    }
    EXPECT_EQ(frame.occupiedCellList(dims), cpu) << dims.x << "x" << dims.y << "x" << dims.z;
  }
  EXPECT_EQ(gpu::passCounts().dispatches, dispatches1);  // the lists need no new pass
  // A grid not counted yet is counted for its list.
  EXPECT_EQ(frame.occupiedCellList(IVec3(5, 5, 5)), occupiedCells(d, IVec3(5, 5, 5)));
  // The occupied voxels per cell (the whole-scene fallback's bound under spots), cell by cell.
  for (const IVec3& dims : grids)
    EXPECT_EQ(frame.occupiedVoxelsPerCell(dims), occupiedVoxelsPerCell(d, dims))
        << dims.x << "x" << dims.y << "x" << dims.z;
  gpu::checkGl("cell occupancy");
}

// The lamp model's k_l (LampModel::k: σt·D at a point or spot light inside the box, 0 for one
// outside and a directional light) and min_l m_l at the box's diagonal are looked up on the
// device once per lights and density (gpu::deviceLights, lamp_k.comp.glsl), not by every pass at
// every step: the values are the CPU's, a second request keeps them without a pass, and a moved
// light makes one pass more.
TEST(GpuComputePipeline, TheLampModelIsLookedUpOncePerLightsAndDensity) {
  SCATTERLAB_REQUIRE_GPU();
  Json doc = homogeneousBoxDoc(1.0f, 3.0f, 0.8f, Vec3(0.3f, 0.4f, 0.5f), 1.0f, 16, 12, 20);
  doc["medium"]["density"] = {
      {"type", "gaussians"},
      {"blobs", Json::array({{{"center", {0.35, 0.45, 0.5}}, {"radius", 0.2}, {"weight", 2.0}},
                             {{"center", {0.7, 0.6, 0.4}}, {"radius", 0.15}, {"weight", 1.0}}})}};
  doc["lights"].push_back({{"type", "spot"},
                           {"position", {0.72, 0.61, 0.41}},
                           {"direction", {0, -1, 0}},
                           {"intensity", {1, 1, 1}},
                           {"inner_deg", 20},
                           {"outer_deg", 30}});
  doc["lights"].push_back({{"type", "point"}, {"position", {2, 2, 2}}, {"intensity", {1, 1, 1}}});
  doc["lights"].push_back(
      {{"type", "directional"}, {"direction", {0, -1, 0}}, {"irradiance", {1, 1, 1}}});
  const Scene scene = sceneFromJson(doc);
  ASSERT_EQ(scene.lights.size(), 4u);
  const DensityGrid density = buildDensityVolume(scene);
  const gpu::Volume v = gpu::uploadDensity(density);
  const long long before = gpu::passCounts().dispatches;
  const auto lights = gpu::deviceLights(scene, v, nullptr);
  EXPECT_EQ(gpu::passCounts().dispatches - before, 1);
  EXPECT_EQ(gpu::deviceLights(scene, v, nullptr), lights);  // kept: no upload, no pass
  EXPECT_EQ(gpu::passCounts().dispatches - before, 1);
  std::vector<gpu::GpuLight> got(scene.lights.size());
  lights->buffer.read(got.data(), got.size() * sizeof(gpu::GpuLight));
  const LampModel cpu(scene, density);
  float m = 1.0f;
  const float diagonal = glm::length(scene.medium.bounds.extent());
  for (std::size_t i = 0; i < got.size(); ++i) {
    // The GPU's trilinear lookup against Grid3::sample (densityAtIndex's CPU twin).
    EXPECT_NEAR(got[i].lampK, cpu.k(i), 1e-6f * std::max(1.0f, cpu.k(i))) << "light " << i;
    m = std::min(m, cpu(i, diagonal));
  }
  EXPECT_GT(cpu.k(0), 0.0f);
  EXPECT_GT(cpu.k(1), 0.0f);
  EXPECT_EQ(got[2].lampK, 0.0f);  // outside the box
  EXPECT_EQ(got[3].lampK, 0.0f);  // directional
  EXPECT_LT(m, 1.0f);
  EXPECT_NEAR(got[0].lampMin, m, 1e-6f);  // lights[0].lamp.y: min_l m_l(diagonal)
  Scene moved = scene;
  moved.lights[0].position += Vec3(0.01f);
  EXPECT_NE(gpu::deviceLights(moved, v, nullptr), lights);
  EXPECT_EQ(gpu::passCounts().dispatches - before, 2);
  // No lamp inside the box: no pass, k_l = 0 and min_l m_l = 1 as packed.
  Scene outside = scene;
  outside.lights.erase(outside.lights.begin(), outside.lights.begin() + 2);
  const auto far = gpu::deviceLights(outside, v, nullptr);
  EXPECT_EQ(gpu::passCounts().dispatches - before, 2);
  gpu::GpuLight first;
  far->buffer.read(&first, sizeof first);
  EXPECT_EQ(first.lampK, 0.0f);
  EXPECT_EQ(first.lampMin, 1.0f);
  gpu::checkGl("lamp model");
}

}  // namespace
}  // namespace scatterlab::testing
