/// Every GPU stage against its CPU twin on the same input (issue 6 tolerances), on llvmpipe in
/// CI. Scenes are tiny so that each test takes a few seconds at most on a software rasteriser.

#include <unistd.h>
#include <cstdio>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <random>

#include "core/stages.h"
#include "cpu/per_voxel.h"
#include "cpu/ray_marcher.h"
#include "gpu/frame.h"
#include "gpu/reconstructions.h"
#include "gpu/slice_marcher.h"
#include "gpu/tracing.h"
#include "gpu/volume.h"
#include "gpu/volume_tracer.h"
#include "gpu_support.h"
#include "media/procedural.h"
#include "shading/transport.h"
#include "shading/view_march.h"

namespace scatterlab::testing {
namespace {

/// |a − b| ≤ tol·(|b| + floor) per component, where floor keeps near-zero values from
/// demanding impossible relative accuracy.
::testing::AssertionResult close3(const Vec3& a, const Vec3& b, float tol, float floor) {
  for (int c = 0; c < 3; ++c)
    if (!(std::abs(a[c] - b[c]) <= tol * (std::abs(b[c]) + floor)))
      return ::testing::AssertionFailure() << "channel " << c << ": gpu " << a[c] << " vs cpu "
                                           << b[c] << " (tol " << tol << ", floor " << floor << ")";
  return ::testing::AssertionSuccess();
}

void expectNoGlError() {
  EXPECT_EQ(glGetError(), GLenum(GL_NO_ERROR));
}

TEST(GpuDensitySplat, MatchesGaussianDensityBuild) {
  SCATTERLAB_REQUIRE_GPU();
  const Scene scene = sceneFromJson(blobSceneDoc(24, 8, 6));
  const auto& gauss = dynamic_cast<const GaussianDensity&>(*scene.medium.density);
  const IVec3 dims(24, 20, 18);  // not a cube: catches axis mix-ups
  DensityGrid cpu(scene.medium.bounds, dims);
  gauss.build(cpu);
  // The paper's slice splat (the compute gather: test_compute_pipeline.cpp).
  const gpu::Volume v =
      gpu::splatGaussians(gauss.blobs(), scene.medium.bounds, dims, nullptr, GpuPipeline::Raster);
  const DensityGrid gpuGrid = gpu::readDensity(v);
  expectNoGlError();
  float maxD = 0;
  for (float d : cpu.data()) maxD = std::max(maxD, d);
  int bad = 0;
  for (size_t i = 0; i < cpu.size(); ++i) {
    const float c = cpu.data()[i], g = gpuGrid.data()[i];
    if (!(std::abs(g - c) <= 1e-4f * std::max(c, 1e-3f * maxD)) && ++bad < 5)
      ADD_FAILURE() << "voxel " << i << ": gpu " << g << " vs cpu " << c;
  }
  EXPECT_EQ(bad, 0);
}

std::vector<RadianceSample> randomSamples(int n, unsigned seed, bool withRadiance) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<float> u(0.0f, 1.0f), s(-2.0f, 2.0f);
  std::vector<RadianceSample> out = std::vector<RadianceSample>(size_t(n));
  for (RadianceSample& r : out) {
    r.position = Vec3(u(rng), u(rng), u(rng));
    r.radius = 0.12f + 0.25f * u(rng);
    if (withRadiance) {
      r.S = Vec3(1.0f + u(rng), 0.5f + u(rng), 2.0f * u(rng) + 0.2f);
      for (Vec3& g : r.dS) g = Vec3(s(rng), s(rng), s(rng));
    }
  }
  return out;
}

TEST(GpuVolumeTracer, SAndGradientMatchCpuTracing) {
  SCATTERLAB_REQUIRE_GPU();
  const Scene scene = sceneFromJson(blobSceneDoc(16, 8, 6));
  DensityGrid density(scene.medium.bounds, scene.medium.resolution);
  scene.medium.density->build(density);
  const float delta1 = 1.0f / 16, delta2 = 1.0f / 32;
  PipelineSettings ps;
  ps.delta1 = delta1;
  ps.delta2 = delta2;
  auto eval = radianceEvaluators().get("volume-tracer", "evaluator").on[int(Backend::Gpu)](ps);
  gpu::GpuFrame frame(density);
  std::vector<RadianceSample> samples = randomSamples(48, 7, false);
  samples[0].position = Vec3(0.0f, 0.5f, 1.0f);  // on the box surface
  samples[1].position = Vec3(0.5f, 1.2f, 0.5f);  // outside the box, inside the spot cone
  eval->evaluate(frame, scene, samples, true);
  expectNoGlError();

  const SourceRadiance source(scene, density, delta1);
  const Vec3 eye = scene.camera.position;
  const auto S = [&](const Vec3& x) { return source(x, glm::normalize(eye - x)); };
  std::vector<Vec3> cs, cg;
  float sMax = 0, gMax = 0;
  for (const RadianceSample& r : samples) {
    cs.push_back(S(r.position));
    for (int a = 0; a < 3; ++a) {
      Vec3 e(0.0f);
      e[a] = delta2;
      cg.push_back((S(r.position + e) - S(r.position - e)) / (2.0f * delta2));
      gMax = std::max(gMax, glm::length(cg.back()));
    }
    sMax = std::max(sMax, glm::length(cs.back()));
  }
  ASSERT_GT(sMax, 0.0f);
  for (size_t i = 0; i < samples.size(); ++i) {
    EXPECT_TRUE(close3(samples[i].S, cs[i], 1e-3f, 1e-3f * sMax)) << "S of sample " << i;
    for (int a = 0; a < 3; ++a)
      EXPECT_TRUE(close3(samples[i].dS[a], cg[3 * i + a], 1e-3f, 1e-2f * gMax))
          << "dS/d"
          << "xyz"[a] << " of sample " << i;
  }
  // S only: gradients left zero.
  std::vector<RadianceSample> only = samples;
  eval->evaluate(frame, scene, only, false);
  EXPECT_TRUE(close3(only[3].S, cs[3], 1e-3f, 1e-3f * sMax));
  EXPECT_EQ(only[3].dS[1], Vec3(0.0f));
}

/// The tracer is parallel over (sample, point, light) (gpu::tracerShape): 40 lights (64 lanes,
/// 24 of them without a light), among them red spot lights whose cones most samples lie outside of
/// while no other light is red (the factored V's cones-ignored path, factoredNeedsFree), traced in
/// each value space against the CPU evaluator; and at least one invocation per sample and light.
TEST(GpuVolumeTracer, FortyLightsSplitBetweenLanesMatchTheCpu) {
  SCATTERLAB_REQUIRE_GPU();
  Json doc = blobSceneDoc(16, 8, 6);
  std::mt19937 rng(5);
  std::uniform_real_distribution<float> u(0.0f, 1.0f);
  doc["lights"] = Json::array();
  for (int i = 0; i < 40; ++i) {
    const Json pos = {2.0f * u(rng) - 0.5f, 2.0f * u(rng) - 0.5f, 2.0f * u(rng) - 0.5f};
    if (i % 8 == 0)
      doc["lights"].push_back({{"type", "spot"},
                               {"position", pos},
                               {"direction", {0.5f - u(rng), -1, 0.5f - u(rng)}},
                               {"intensity", {2.0f + u(rng), 0, 0}},
                               {"inner_deg", 6},
                               {"outer_deg", 12}});
    else if (i % 8 == 1)
      doc["lights"].push_back({{"type", "directional"},
                               {"direction", {u(rng) - 0.5f, -1, u(rng) - 0.5f}},
                               {"irradiance", {0, 0.05f * u(rng), 0.05f * u(rng)}}});
    else
      doc["lights"].push_back(
          {{"type", "point"}, {"position", pos}, {"intensity", {0, 0.3f * u(rng), 0.3f * u(rng)}}});
  }
  const Scene scene = sceneFromJson(doc);
  ASSERT_EQ(scene.lights.size(), 40u);
  DensityGrid density(scene.medium.bounds, scene.medium.resolution);
  scene.medium.density->build(density);
  const gpu::TracerShape shape = gpu::tracerShape(scene.lights.size(), true);
  EXPECT_EQ(shape.lanes, 64);
  EXPECT_EQ(shape.slots, 1);
  // Beyond 64 lights the lanes stride over them (lane k: lights k, k + 64, …).
  EXPECT_EQ(gpu::tracerShape(100, true).lanes, 64);
  // Most samples lie outside every red cone: A's red is 0 there (the cones-ignored path).
  const std::vector<RadianceSample> positions = randomSamples(37, 9, false);
  const LightFactor lightFactor(scene);
  int redless = 0;
  for (const RadianceSample& r : positions)
    redless +=
        lightFactor(r.position, glm::normalize(scene.camera.position - r.position)).r == 0.0f;
  EXPECT_GE(redless, 20);
  struct Space {
    const char* name;
    bool factor, log;
    float tolS, tolGrad;
  };
  // Largest |gpu − cpu| / (|cpu| + 1e-3·max), value and gradient, measured on llvmpipe (Mesa
  // 22.3.6; GCC 12 build): S 3.7e-7, 7.4e-5; V 3.8e-7, 6.5e-4; ln V 1.7e-4, 6.5e-4. A clang 14
  // build: ∇V 1.02e-3. NVIDIA H200 (driver 580.159.04, 2026-11-27): ln V 2.63e-4 (the rest
  // within the llvmpipe limits). With SCATTERLAB_GPU_IMPRECISE=2 / 4 (2026-12-07): S 8.9e-7 /
  // 9.95e-7, 1.33e-4 / 1.77e-4; V 5.3e-7 / 7.3e-7, 6.9e-4 / 8.6e-4; ln V 1.2e-4 / 2.5e-4,
  // 4.6e-4 / 1.03e-3. Tolerances 1.5x the largest.
  for (const Space sp :
       {Space{"S", false, false, 1.5e-6f, 2.7e-4f}, Space{"V", true, false, 1.1e-6f, 1.6e-3f},
        Space{"ln V", true, true, 4e-4f, 1.6e-3f}}) {
    PipelineSettings ps;
    ps.delta1 = 1.0f / 16;
    ps.delta2 = 1.0f / 32;
    ps.factorLights = sp.factor;
    ps.logSpace = sp.log;
    const auto& decl = radianceEvaluators().get("volume-tracer", "evaluator");
    auto gpuEval = decl.on[int(Backend::Gpu)](ps);
    auto cpuEval = decl.on[int(Backend::Cpu)](ps);
    std::vector<RadianceSample> g = positions, c = g;
    gpu::GpuFrame frame(density);
    const long long before = gpu::passCounts().invocations[gpu::kTracerPass];
    gpuEval->evaluate(frame, scene, g, true);
    const long long invocations = gpu::passCounts().invocations[gpu::kTracerPass] - before;
    expectNoGlError();
    EXPECT_GE(invocations, (long long)(g.size() * scene.lights.size())) << sp.name;
    HostFrame host(density);
    cpuEval->evaluate(host, scene, c, true);
    float sMax = 0.0f, gMax = 0.0f, sErr = 0.0f, gErr = 0.0f;
    for (const RadianceSample& r : c) {
      sMax = std::max(sMax, glm::length(r.S));
      for (const Vec3& d : r.dS) gMax = std::max(gMax, glm::length(d));
    }
    ASSERT_GT(sMax, 0.0f) << sp.name;
    for (std::size_t i = 0; i < g.size(); ++i)
      for (int ch = 0; ch < 3; ++ch) {
        sErr = std::max(sErr,
                        std::abs(g[i].S[ch] - c[i].S[ch]) / (std::abs(c[i].S[ch]) + 1e-3f * sMax));
        for (int a = 0; a < 3; ++a)
          gErr = std::max(gErr, std::abs(g[i].dS[a][ch] - c[i].dS[a][ch]) /
                                    (std::abs(c[i].dS[a][ch]) + 1e-3f * gMax));
      }
    std::printf("forty lights, %s: value %.3g, gradient %.3g\n", sp.name, double(sErr),
                double(gErr));
    EXPECT_LE(sErr, sp.tolS) << sp.name;
    EXPECT_LE(gErr, sp.tolGrad) << sp.name;
  }
}

TEST(GpuGradientSplat, MatchesDirectEq4) {
  SCATTERLAB_REQUIRE_GPU();
  const Scene scene = sceneFromJson(blobSceneDoc(20, 8, 6));
  const IVec3 dims(20, 18, 16);
  DensityGrid density(scene.medium.bounds, dims);
  scene.medium.density->build(density);
  const std::vector<RadianceSample> samples = randomSamples(40, 11, true);
  auto rec = reconstructions().get("gradient", "reconstruction").on[int(Backend::Gpu)]({});
  gpu::GpuFrame frame(density);
  const ReconstructionStats st = rec->reconstruct(frame, scene, samples, dims, nullptr);
  const RadianceGrid out = gpu::readRadiance(frame.radiance);
  expectNoGlError();

  long long uncovered = 0, covered = 0;
  int bad = 0;
  const VoxelOccupancy occupied(density, out);
  for (int k = 0; k < dims.z; ++k)
    for (int j = 0; j < dims.y; ++j)
      for (int i = 0; i < dims.x; ++i) {
        const Vec3 x = out.cellCenter(i, j, k);
        Vec3 sum(0.0f);
        float wsum = 0.0f;
        for (const RadianceSample& s : samples) {
          const float d = glm::length(x - s.position);
          if (!(d < s.radius)) continue;
          const float W = s.radius / std::max(d, kSingularEps * s.radius);
          sum += W * s.taylor(x);
          wsum += W;
        }
        // Eq. 4, clamped to non-negative as the CPU reconstruction (clampNonNegative); an
        // occupied voxel no sphere covers takes the nearest sample's S (lowest index on ties).
        Vec3 want = wsum > 0 ? glm::max(sum / wsum, Vec3(0.0f)) : Vec3(0.0f);
        if (wsum > 0) {
          ++covered;
        } else if (occupied(i, j, k)) {
          ++uncovered;
          float best = kInfinity;
          for (const RadianceSample& s : samples) {
            const Vec3 d = x - s.position;
            if (glm::dot(d, d) < best) {
              best = glm::dot(d, d);
              want = glm::max(s.S, Vec3(0.0f));
            }
          }
        }
        const auto r = close3(out.at(i, j, k), want, 1e-3f, 1e-2f);
        if (!r && ++bad < 5)
          ADD_FAILURE() << "voxel " << i << "," << j << "," << k << ": " << r.message();
      }
  EXPECT_EQ(bad, 0);
  EXPECT_GT(covered, 0);
  // The frame reads the GPU's count after the frame (GpuFrame::deferStats), into its report.
  (void)st;
  RenderStats report;
  frame.report(report);
  EXPECT_EQ(report.extra.at("uncovered_voxels").get<long long>(), uncovered);
  EXPECT_EQ(report.extra.at("host_waits").get<long long>(), 1);  // the test's readRadiance
}

TEST(GpuPerVoxel, MatchesCpuPerVoxelRadiance) {
  SCATTERLAB_REQUIRE_GPU();
  const Scene scene = sceneFromJson(blobSceneDoc(16, 8, 6));
  DensityGrid density(scene.medium.bounds, scene.medium.resolution);
  scene.medium.density->build(density);
  const float delta1 = 1.0f / 16;
  RadianceGrid cpu(scene.medium.bounds, IVec3(16, 14, 12));
  const PerVoxelStats cst = buildPerVoxelRadiance(scene, density, delta1, cpu, nullptr);
  ReconstructionStats gst;
  const gpu::Volume d = gpu::uploadDensity(density);
  const gpu::Volume v =
      gpu::PerVoxelGpu(delta1).build(scene, d, cpu.bounds(), cpu.dims(), &gst, nullptr);
  const RadianceGrid g = gpu::readRadiance(v);
  expectNoGlError();
  EXPECT_EQ(gst.traced, cst.traced);
  EXPECT_EQ(gst.skipped, cst.skipped);
  EXPECT_GT(cst.skipped, 0) << "the scene should exercise the empty-voxel skip";
  float sMax = 0;
  for (const Vec3& s : cpu.data()) sMax = std::max(sMax, glm::length(s));
  int bad = 0;
  for (size_t i = 0; i < cpu.size(); ++i) {
    const auto r = close3(g.data()[i], cpu.data()[i], 1e-3f, 1e-3f * sMax);
    if (!r && ++bad < 5) ADD_FAILURE() << "voxel " << i << ": " << r.message();
  }
  EXPECT_EQ(bad, 0);
}

/// CPU marcher and slice marcher on the same volumes. `lightInside`: the point light sits in
/// the medium, where S has a 1/d² spike; both are midpoint rules but at different points
/// (per-ray steps vs view-depth slabs), so near the spike they differ by more than 0.5% at
/// practical steps (measured: 1.07% at half a voxel, one pixel next to the light) and agree
/// once the step is small; with the light outside the medium they agree at half a voxel.
double sliceVsCpu(bool lightInside, float stepVoxels, const char* slicing = "view-planes") {
  Json doc = blobSceneDoc(24, 32, 24);
  if (!lightInside) doc["lights"][0]["position"] = {1.25, 0.8, 0.3};
  Scene scene = sceneFromJson(doc);
  scene.background = Vec3(0.05f, 0.1f, 0.2f);
  scene.camera.position = Vec3(1.6f, 1.1f, -1.5f);  // oblique: slices not aligned with axes
  DensityGrid density(scene.medium.bounds, scene.medium.resolution);
  scene.medium.density->build(density);
  RadianceGrid radiance(scene.medium.bounds, IVec3(20));
  buildPerVoxelRadiance(scene, density, 1.0f / 24, radiance, nullptr);
  MarchSettings ms;
  ms.step = stepVoxels / 24;
  ms.minTransmittance = 0.0f;
  const Vec3 s = radiance.indexScale(), o = radiance.indexOffset();
  const auto lookup = [&](const Vec3& x, const Vec3&) { return radiance.sampleIndex(x * s + o); };
  const Image cpu = marchImage(scene, density, lookup, ms, nullptr);

  PipelineSettings ps;
  ps.march = ms;
  ps.integratorKeys.set(RayMarcherSettings{
      .slicing = std::string(slicing) == "ray-steps" ? Slicing::RaySteps : Slicing::ViewPlanes});
  ps.gpuPipeline = GpuPipeline::Raster;  // the paper's slice marcher (the compute march:
                                         // test_compute_pipeline.cpp)
  auto integ = integrators().get("ray-marcher", "integrator").on[int(Backend::Gpu)](ps);
  gpu::GpuFrame frame(density);
  frame.radiance = gpu::uploadRadiance(radiance);
  const Image g = integ->integrate(frame, scene, nullptr);
  expectNoGlError();
  EXPECT_EQ(g.width(), 32);
  EXPECT_EQ(g.height(), 24);
  // Orientation: the top-left pixel of both images is background (no flip).
  EXPECT_NEAR(g.at(0, 0).z, cpu.at(0, 0).z, 1e-4f);
  const double err = relL2(g, cpu);
  std::printf("slice marcher vs CPU marcher (light %s, step %.3g voxel): relative L2 %.3g\n",
              lightInside ? "inside" : "outside", stepVoxels, err);
  return err;
}

TEST(GpuSliceMarcher, MatchesCpuMarcherOnTheSameVolumes) {
  SCATTERLAB_REQUIRE_GPU();
  EXPECT_LT(sliceVsCpu(false, 0.5f), 0.005);
}

TEST(GpuSliceMarcher, AgreesWithCpuMarcherNearALightInsideTheMediumAtSmallSteps) {
  SCATTERLAB_REQUIRE_GPU();
  EXPECT_LT(sliceVsCpu(true, 0.125f), 0.005);
}

TEST(GpuSliceMarcher, RayStepLayersMatchCpuMarcherNearALightInsideTheMedium) {
  SCATTERLAB_REQUIRE_GPU();
  EXPECT_LT(sliceVsCpu(true, 0.5f, "ray-steps"), 0.005);
}

TEST(GpuPerVoxelMethod, EndToEndMatchesCpuMethod) {
  SCATTERLAB_REQUIRE_GPU();
  Json doc = blobSceneDoc(20, 32, 24);
  doc["lights"][0]["position"] = {1.25, 0.8, 0.3};  // see sliceVsCpu on lights inside
  doc["render"]["march_step"] = 0.5 / 20;
  const Scene scene = sceneFromJson(doc);
  const RenderResult cpu = createMethod(scene, "", "cpu")->render(scene, nullptr);
  const RenderResult gpu = createMethod(scene, "", "gpu")->render(scene, nullptr);
  expectNoGlError();
  EXPECT_EQ(gpu.stats.backend, "gpu");
  EXPECT_EQ(gpu.stats.device, gpu::context().info().renderer);
  EXPECT_EQ(gpu.stats.method, "per-voxel");
  EXPECT_EQ(gpu.stats.extra["traced_voxels"], cpu.stats.extra["traced_voxels"]);
  EXPECT_TRUE(gpu.stats.extra.contains("gpu_ms"));
  const double err = relL2(gpu.image, cpu.image);
  std::printf("per-voxel gpu vs cpu: relative L2 %.3g\n", err);
  EXPECT_LT(err, 0.005);
  // auto: llvmpipe is not a hardware GPU, so auto stays on the CPU there.
  const RenderResult a = createMethod(scene, "", "auto")->render(scene, nullptr);
  EXPECT_EQ(a.stats.backend, gpu::context().info().hardware ? "gpu" : "cpu");
}

}  // namespace
}  // namespace scatterlab::testing

namespace scatterlab::testing {
namespace {

// A medium that is not a sum of Gaussians is built on the CPU and uploaded. In a fresh process
// (the tool) nothing has made the GL context current before the density stage: the frame must.
TEST(GpuMethods, UploadedDensityInAFreshProcessMatchesCpu) {
  SCATTERLAB_REQUIRE_GPU();
  const std::string dir = ::testing::TempDir() + "gpu_fresh_" + std::to_string(::getpid());
  std::filesystem::create_directories(dir);
  Json doc = testing::homogeneousBoxDoc(0.8f, 2.0f, 0.6f, Vec3(0.3f, 1.4f, 0.4f), 3.0f, 24, 18, 16);
  doc["render"] = {
      {"sampler", {{"type", "jittered"}, {"count", 64}}}, {"levels", {4, 8}}, {"voxel_switch", 0}};
  std::ofstream(dir + "/box.json") << doc.dump();
  for (const char* m : {"per-voxel", "gradient", "adaptive"}) {
    for (const char* b : {"cpu", "gpu"}) {
      const std::string cmd = std::string(SCATTERLAB_CLI) + " render " + dir + "/box.json -q -o " +
                              dir + "/" + m + "_" + b + ".exr --method " + m + " --backend " + b;
      ASSERT_EQ(std::system(cmd.c_str()), 0) << cmd;
    }
    const double err =
        relL2(readExr(dir + "/" + m + "_gpu.exr"), readExr(dir + "/" + m + "_cpu.exr"));
    std::printf("%s gpu vs cpu (uploaded density, fresh process): relative L2 %.3g\n", m, err);
    // Measured on llvmpipe (Mesa 22.3.6), 2026-11-26 (compute pipeline): 2.92e-7 / 3.04e-7 /
    // 3.2e-7; on an NVIDIA H200 (driver 580), 2026-11, issue 23 (raster pipeline): up to 6.0e-5.
    // ×1.5 of the larger.
    EXPECT_LT(err, 9.0e-5);
  }
  std::filesystem::remove_all(dir);
}

}  // namespace
}  // namespace scatterlab::testing

namespace scatterlab::testing {
namespace {

// The CPU march's keys have no meaning for the GPU's slice marcher: a scene that sets them
// renders on the GPU and names them in the stats as unused (as `slicing` on the CPU), instead
// of being ignored silently.
TEST(GpuStages, CpuMarchKeysAreReportedUnused) {
  SCATTERLAB_REQUIRE_GPU();
  initialize();
  Json doc = blobSceneDoc(16, 32, 24);
  doc["render"]["method"] = "gradient";
  doc["render"]["march_scale"] = 2;
  doc["render"]["fast_march"] = false;
  const Scene s = parseScene(doc, ".");
  const RenderResult gpu = createMethod(s, "", "gpu")->render(s, nullptr);
  ASSERT_TRUE(gpu.stats.extra.contains("unused_keys"));
  EXPECT_EQ(gpu.stats.extra["unused_keys"],
            Json::array({"render.fast_march", "render.march_scale"}));
  const RenderResult cpu = createMethod(s, "", "cpu")->render(s, nullptr);
  EXPECT_FALSE(cpu.stats.extra.contains("unused_keys"));
}

}  // namespace
}  // namespace scatterlab::testing
