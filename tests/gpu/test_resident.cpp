/// The GPU pipeline kept resident (issue 14, part 5): .sog density built on the GPU from the
/// Gaussians and a sparsely uploaded residual, and GL objects reused across the frames of one
/// Renderer. On llvmpipe in CI, with tiny scenes.

#include <algorithm>
#include <cstdio>
#include <fstream>
#include <tuple>

#include "api/scatterlab.h"
#include "gpu/frame.h"
#include "gpu/gl.h"
#include "gpu/volume.h"
#include "gpu_support.h"
#include "media/sog.h"
#include "support/cli.h"

namespace scatterlab::testing {
namespace {

/// A .sog model over [0,1]³ (lattice 10×12×8, not a cube) with three Gaussians and residual
/// entries of both signs, one large enough to clamp D at 0 around it.
SogModel smallSog() {
  SogModel m;
  m.gaussians = {{Vec3(0.5f, 0.5f, 0.5f), 0.18f, 1.0f},
                 {Vec3(0.3f, 0.62f, 0.4f), 0.1f, 0.7f},
                 {Vec3(0.8f, 0.3f, 0.65f), 0.12f, 0.9f}};
  m.residual = ResidualHash(Box{Vec3(0), Vec3(1)}, IVec3(10, 12, 8), 8, 0.01f);
  m.residual.insert(0, 5);
  m.residual.insert(123, -40);
  m.residual.insert(500, 127);
  m.residual.insert(640, -128);  // (0, 4, 5): D̃ ≈ 0 there, so max(0, D̃ + F) clamps
  for (std::uint32_t k = 300; k < 340; ++k) m.residual.insert(k, std::int16_t(int(k % 17) - 8));
  return m;
}

TEST(GpuResident, SogDensitySplattedOnTheGpuEqualsTheCpuSplat) {
  SCATTERLAB_REQUIRE_GPU();
  const auto sog = std::make_shared<const SogDensity>(smallSog(), "test model");
  // A render grid unlike the lattice (and beyond it on one side: F = 0 outside the lattice box).
  const Box bounds{Vec3(0.0f), Vec3(1.0f, 1.0f, 1.1f)};
  const IVec3 dims(24, 20, 18);
  DensityGrid cpu(bounds, dims);
  sog->build(cpu);
  bool uploaded = false;
  const gpu::Volume v = gpu::splatSog(sog, bounds, dims, nullptr, &uploaded);
  const DensityGrid g = gpu::readDensity(v);
  gpu::checkGl("sog density");
  DensityGrid gaussiansOnly(bounds, dims);
  sog->model().splat(gaussiansOnly, false);
  float maxD = 0.0f, worst = 0.0f;
  for (float d : cpu.data()) maxD = std::max(maxD, d);
  int clamped = 0;
  for (std::size_t i = 0; i < cpu.size(); ++i) {
    worst = std::max(worst, std::abs(g.data()[i] - cpu.data()[i]));
    const Vec3 p = cpu.cellCenter(int(i % 24), int(i / 24 % 20), int(i / 480));
    clamped += gaussiansOnly.data()[i] + sog->model().residual.sample(p) < 0.0f;
  }
  std::printf("sog density: max |gpu - cpu| = %.3g (max D %.3g), %d clamped voxels\n", worst, maxD,
              clamped);
  // Measured on llvmpipe: 1.79e-7 with max D 0.959 (the Gaussians' exp in the splat; F is added
  // with the CPU's operations); on an NVIDIA H200 (driver 580), 2026-11, issue 23: 2.98e-7
  // (hardware exp). 1.5x the larger.
  const float tol = 4.5e-7f;
  EXPECT_LE(worst, tol);
  EXPECT_GT(clamped, 0);
  // The same model object again (another resolution): the residual lattice is kept.
  bool again = true;
  const gpu::Volume w = gpu::splatSog(sog, bounds, IVec3(16), nullptr, &again);
  EXPECT_FALSE(again);
  DensityGrid cpu16(bounds, IVec3(16));
  sog->build(cpu16);
  const DensityGrid g16 = gpu::readDensity(w);
  float worst16 = 0.0f;
  for (std::size_t i = 0; i < cpu16.size(); ++i)
    worst16 = std::max(worst16, std::abs(g16.data()[i] - cpu16.data()[i]));
  EXPECT_LE(worst16, tol);
  // A copy of the model (e.g. the file read again) is another object: uploaded again.
  const auto copy = std::make_shared<const SogDensity>(smallSog(), "test model");
  bool copied = false;
  gpu::splatSog(copy, bounds, dims, nullptr, &copied);
  EXPECT_TRUE(copied);
}

class GpuSogMethod : public TempDirTest {
 protected:
  GpuSogMethod() : TempDirTest("gpu_sog") {}
};

/// A .sog medium end to end: `per-voxel` on the GPU (density splatted, residual added on the
/// GPU) against the CPU method (SogModel::splat).
TEST_F(GpuSogMethod, PerVoxelImageMatchesCpu) {
  SCATTERLAB_REQUIRE_GPU();
  const std::string file = out("small.sog");
  writeSog(file, smallSog());
  Json doc = blobSceneDoc(20, 32, 24);
  doc["medium"]["density"] = {{"type", "sog"}, {"file", file}};
  initialize();
  const Scene s = parseScene(doc, ".");
  const RenderResult cpu = createMethod(s, "per-voxel", "cpu")->render(s, nullptr);
  const RenderResult gpu = createMethod(s, "per-voxel", "gpu")->render(s, nullptr);
  gpu::checkGl("sog per-voxel");
  EXPECT_EQ(gpu.stats.extra.at("density_construction"), "gpu splat");
  const double err = relL2(gpu.image, cpu.image);
  std::printf("sog per-voxel, gpu vs cpu: relative L2 %.3g\n", err);
  // Measured on llvmpipe: 9.96e-7 (compute pipeline; the per-voxel stage's own CPU/GPU
  // difference, docs/gpu.md); on an NVIDIA H200 (driver 580), 2026-11, issue 23 (raster
  // pipeline): 4.1e-4 (hardware exp in every traced voxel, over the smoke's long dense light
  // paths). 1.5x the larger.
  EXPECT_LE(err, 6.2e-4);
}

TEST(GpuRecycling, SameDescriptionTakesTheNameOverOnlyInsideAScope) {
  SCATTERLAB_REQUIRE_GPU();
  gpu::context();
  GLuint name = 0;
  {
    const gpu::Buffer b(64, nullptr, 0, "outside");
    name = b.id();
  }
  {
    gpu::RecyclingScope scope;
    const long long reused0 = gpu::glObjectCounts().reused;
    GLuint texName = 0;
    {
      const float ones[4] = {1, 1, 1, 1};
      const gpu::Buffer b(16, ones, 0, "first");
      name = b.id();
      gpu::Texture t = gpu::Texture::make3D(GL_R32F, 4, 4, 4, "first texture");
      glClearTexImage(t.id(), 0, GL_RED, GL_FLOAT, ones);
      texName = t.id();
    }
    EXPECT_EQ(gpu::glObjectCounts().free, 2);
    const float data[4] = {1, 2, 3, 4};
    const gpu::Buffer same(16, data, 0, "second");
    EXPECT_EQ(same.id(), name);  // taken over, with the new data
    float back[4] = {};
    same.read(back, sizeof back);
    EXPECT_EQ(back[3], 4.0f);
    const gpu::Buffer other(32, nullptr, 0, "other size");
    EXPECT_NE(other.id(), name);
    const gpu::Texture t = gpu::Texture::make3D(GL_R32F, 4, 4, 4, "second texture");
    EXPECT_EQ(t.id(), texName);  // taken over, cleared to zero as a new texture reads
    std::vector<float> texels(64, -1.0f);
    glGetTextureImage(t.id(), 0, GL_RED, GL_FLOAT, GLsizei(texels.size() * sizeof(float)),
                      texels.data());
    EXPECT_EQ(*std::max_element(texels.begin(), texels.end()), 0.0f);
    EXPECT_EQ(gpu::glObjectCounts().reused - reused0, 2);
  }
  EXPECT_EQ(gpu::glObjectCounts().free, 0);  // the scope's end deleted the free list
  gpu::checkGl("recycling");
}

TEST(GpuBuffers, StorageIsASizeClassSoNearSizesShareRecycledBuffers) {
  // Exact up to 256 bytes; then the next quarter of the power of two below (eighths above
  // 1 MiB): a set that grows by a few samples between frames fits the buffer it had.
  EXPECT_EQ(gpu::Buffer::storageFor(0), 4u);
  EXPECT_EQ(gpu::Buffer::storageFor(100), 100u);
  EXPECT_EQ(gpu::Buffer::storageFor(256), 256u);
  EXPECT_EQ(gpu::Buffer::storageFor(257), 320u);      // 256 + 64
  EXPECT_EQ(gpu::Buffer::storageFor(9600), 10240u);   // 300 samples of 32 B: 8192 + 2048
  EXPECT_EQ(gpu::Buffer::storageFor(10240), 10240u);  // 320 samples: the same storage
  EXPECT_EQ(gpu::Buffer::storageFor(3u << 20), 3u << 20);
  EXPECT_EQ(gpu::Buffer::storageFor((3u << 20) + 1), (3u << 20) + (1u << 18));
}

/// The blob scene with its spot light moved per frame.
Json frameDoc(int frame) {
  Json doc = blobSceneDoc(16, 32, 24);
  doc["lights"][1]["position"] = {0.5 + 0.1 * frame, 1.4, 0.5 - 0.05 * frame};
  return doc;
}

RenderResult freshRender(const Json& doc, const std::string& method) {
  initialize();
  const Scene s = parseScene(doc, ".");
  return createMethod(s, method, "gpu")->render(s, nullptr);
}

/// The image a render left on the device (keepImageOnDevice), read back: its RGB.
Image deviceImage(const RenderResult& res) {
  const RenderResult::DeviceImage& d = *res.deviceImage;
  std::vector<float> rgba(std::size_t(d.width) * std::size_t(d.height) * 4);
  gpu::context();  // a Renderer call leaves scatterlab's context current on no thread
  glGetTextureImage(d.texture, 0, GL_RGBA, GL_FLOAT, GLsizei(rgba.size() * sizeof(float)),
                    rgba.data());
  gpu::checkGl("device image read-back");
  Image img(d.width, d.height);
  for (std::size_t i = 0; i < img.pixels().size(); ++i)
    img.pixels()[i] = Vec3(rgba[4 * i], rgba[4 * i + 1], rgba[4 * i + 2]);
  return img;
}

class GpuRendererReuse : public ::testing::TestWithParam<const char*> {};

TEST_P(GpuRendererReuse, FramesEqualFreshRendersAndCreateNoGlObjects) {
  SCATTERLAB_REQUIRE_GPU();
  const std::string method = GetParam();
  const auto doc = [](int f) {
    Json d = frameDoc(f);
    d["render"]["voxel_switch"] = 0;  // adaptive: dynamic sampling, not per-voxel instead
    return d;
  };
  std::vector<Image> fresh;
  for (int f = 0; f < 3; ++f) fresh.push_back(freshRender(doc(f), method).image);
  Renderer r(doc(0), ".", method, "gpu");
  std::vector<long long> created, held;
  long long reusedBefore = gpu::glObjectCounts().reused;
  for (int f = 0; f < 3; ++f) {
    if (f > 0) r.set("lights.1.position=" + frameDoc(f)["lights"][1]["position"].dump());
    const RenderResult res = r.render();
    gpu::checkGl("renderer frame");
    const gpu::GlObjectCounts counts = gpu::glObjectCounts();
    created.push_back(counts.created);
    held.push_back(counts.live + counts.free);
    // Per-stage GPU times (issue 14): every pass's ms belongs to one pipeline stage.
    const Json& byStage = res.stats.extra.at("gpu_timings_ms");
    double passes = 0.0, stages = 0.0;
    for (const auto& [pass, ms] : res.stats.extra.at("gpu_ms").items()) passes += ms.get<double>();
    for (const auto& [stage, ms] : byStage.items()) {
      stages += ms.get<double>();
      bool timed = false;
      for (const auto& [name, wall] : res.stats.timingsMs) timed |= name == stage;
      EXPECT_TRUE(timed) << stage << " is not a stage of timings_ms";
    }
    EXPECT_TRUE(byStage.contains("march"));
    EXPECT_NEAR(stages, passes, 1e-9 * passes);
    EXPECT_NEAR(res.stats.extra.at("gpu_ms_total").get<double>(), passes, 1e-9 * passes);
    const double diff = compareImages(res.image, fresh[std::size_t(f)]).maxAbs;
    std::printf(
        "%s frame %d: max |kept - fresh| = %.3g, GL objects created so far %lld, "
        "taken from the recycler in this frame %lld\n",
        method.c_str(), f, diff, created.back(), counts.reused - reusedBefore);
    reusedBefore = counts.reused;
    // Measured: 0 (the recycled objects are cleared as new ones read; same passes, same order).
    EXPECT_EQ(diff, 0.0) << "frame " << f;
  }
  // Frames 2 and 3 take every object from the recycler: nothing is created, nothing more held.
  EXPECT_EQ(created[1], created[0]);
  EXPECT_EQ(created[2], created[0]);
  EXPECT_EQ(held[2], held[1]);
  // adaptive's sample sets grow and shrink by a few samples as the light sweeps on and back
  // (frames 3, 4, then 1, 0), and the buffers kept for them (sample positions, S, bins, the
  // statistics' staging) have the headroom for it (gpu::Growth::Varies): still nothing created.
  // (Before the headroom, frame 2 made two buffers: bin lists 24 560 → 24 660 bytes, staging
  // 196 464 → 197 344, each just past its size class.)
  if (method != "adaptive") return;
  for (const int at : {3, 4, 1, 0}) {
    r.set("lights.1.position=" + frameDoc(at)["lights"][1]["position"].dump());
    r.render();
    gpu::checkGl("renderer frame");
    EXPECT_EQ(gpu::glObjectCounts().created, created[0]) << "light at " << at;
  }
}

INSTANTIATE_TEST_SUITE_P(Methods, GpuRendererReuse,
                         ::testing::Values("gradient", "adaptive", "per-voxel"));

/// The engine's loop (issue 33) with adaptive: the image left on the device, so the final
/// samples stay there, are binned on the GPU and their statistics are read after the frame. With
/// the light swept out and back the sample sets change size from frame to frame, and no frame
/// after the first makes a GL object. Measured on llvmpipe: 0 in frames 1–4, with and without the
/// headroom of gpu::Growth::Varies (the resident buffers are sized from the levels' capacities,
/// which the light does not change here; GpuRendererReuse's read-back path needs the headroom).
TEST(GpuSteadyFrame, AdaptiveWithASweptLightCreatesNoGlObjects) {
  SCATTERLAB_REQUIRE_GPU();
  const auto doc = [](int f) {
    Json d = frameDoc(f);
    d["render"]["voxel_switch"] = 0;  // dynamic sampling, not per-voxel instead
    return d;
  };
  Renderer r(doc(0), ".", "adaptive", "gpu");
  r.keepImageOnDevice(true);
  r.render();
  const long long first = gpu::glObjectCounts().created;
  for (const int at : {2, 4, 1, 0}) {
    r.set("lights.1.position=" + doc(at)["lights"][1]["position"].dump());
    const RenderResult res = r.render();
    gpu::checkGl("resident frame");
    ASSERT_TRUE(res.deviceImage.has_value());
    EXPECT_EQ(gpu::glObjectCounts().created - first, 0) << "light at " << at;
  }
}

/// Issue 33: a steady Renderer frame — a light moved, the density and the samples kept, the
/// image left on the device — makes the host wait for nothing between the frame's start and the
/// moment someone reads the image: no read-back of S and ∇S (the gather reads them where the
/// tracer wrote them), no count read inside the frame (deferred to the report), no density
/// read for the lamps' Taylor bound (computed on the GPU); for adaptive, no E read per level
/// (the budget's cut decided on the GPU), the final samples assembled and binned on the GPU, and
/// the levels' stats read after the frame. Its image equals a fresh render's (which reads the
/// samples back and bins them on the host: the same lists, the same sums).
class GpuSteadyFrame : public ::testing::TestWithParam<std::tuple<const char*, bool>> {};

TEST_P(GpuSteadyFrame, ALightMovedWaitsForNothing) {
  SCATTERLAB_REQUIRE_GPU();
  const auto [method, paper] = GetParam();
  const auto doc = [paper = paper](int f) {
    Json d = frameDoc(f);  // a point light inside the medium: lamp_model on by default
    d["render"]["paper"] = paper;
    if (!paper) d["render"]["voxel_switch"] = 0;  // dynamic sampling, not per-voxel instead
    return d;
  };
  Renderer r(doc(0), ".", method, "gpu");
  r.keepImageOnDevice(true);
  const RenderResult cold = r.render();
  std::printf("%s%s cold frame: host_waits %lld, dispatches %lld\n", method,
              paper ? " (paper)" : "", cold.stats.extra.at("host_waits").get<long long>(),
              cold.stats.extra.at("dispatches").get<long long>());
  for (int f = 1; f < 3; ++f) {
    r.set("lights.1.position=" + doc(f)["lights"][1]["position"].dump());
    const RenderResult res = r.render();
    const long long waits = res.stats.extra.at("host_waits").get<long long>();
    std::printf("%s%s steady frame %d: host_waits %lld, dispatches %lld\n", method,
                paper ? " (paper)" : "", f, waits,
                res.stats.extra.at("dispatches").get<long long>());
    EXPECT_EQ(waits, 0) << "frame " << f;
    if (std::string(method) != "per-voxel") {
      EXPECT_TRUE(res.stats.extra.at("samples_reused").get<bool>());
    }
    ASSERT_TRUE(res.deviceImage.has_value());
    EXPECT_FALSE(res.stats.extra.contains("image_readback_ms"));
    // The image, read after the frame, equals a fresh render's (which reads its image back).
    const Image onDevice = deviceImage(res);
    Json freshDoc = doc(f);
    const RenderResult freshResult = freshRender(freshDoc, method);
    const Image& fresh = freshResult.image;
    if (std::string(method) == "adaptive") {
      // The count and the levels' stats, read after the frame, are the fresh render's.
      ASSERT_TRUE(res.stats.samples.has_value());
      EXPECT_EQ(*res.stats.samples, *freshResult.stats.samples);
      EXPECT_EQ(res.stats.extra.at("samples_per_level"),
                freshResult.stats.extra.at("samples_per_level"));
      for (const char* key : {"evaluated", "split", "capped", "topped_up", "kept"})
        for (std::size_t l = 0; l < freshResult.stats.extra.at("levels").size(); ++l)
          EXPECT_EQ(res.stats.extra.at("levels")[l].at(key),
                    freshResult.stats.extra.at("levels")[l].at(key))
              << key << " of level " << l;
      EXPECT_TRUE(res.samples.empty());  // left on the device
    }
    const double worst = compareImages(onDevice, fresh).maxAbs;
    std::printf("  max |device image - fresh render| = %.3g\n", worst);
    // Measured on llvmpipe: 0 (the same passes on the same records; the lamp bound computed on
    // the GPU equals the host's on this scene).
    EXPECT_EQ(worst, 0.0) << "frame " << f;
  }
}

/// A's far field in a steady frame (render.far_field): a lamp moved, the grid updated in place
/// for it (two dispatches), its vertex count read after the frame, the image left on the
/// device: no host wait, and the image within rounding of a fresh render (whose grid is built
/// whole).
TEST(GpuSteadyFrame, GradientWithAFarFieldWaitsForNothing) {
  SCATTERLAB_REQUIRE_GPU();
  const auto doc = [](int f) {
    Json d = blobSceneDoc(24, 32, 24);
    d["medium"]["phase"] = {{"type", "isotropic"}};
    d["lights"][0]["position"] = {0.55 + 0.02 * f, 0.55, 0.45};
    d["lights"].push_back(
        {{"type", "point"}, {"position", {0.1, 0.8, 0.2}}, {"intensity", {1, 1, 1}}});
    d["lights"].push_back(
        {{"type", "point"}, {"position", {0.9, 0.2, 0.8}}, {"intensity", {1, 1, 1}}});
    d["render"] = {{"method", "gradient"}, {"voxel_switch", 0}, {"far_field", 3}};
    return d;
  };
  Renderer r(doc(0), ".", "gradient", "gpu");
  r.keepImageOnDevice(true);
  r.render();
  double worst = 0.0;
  for (int f = 1; f < 4; ++f) {
    r.set("lights.0.position=" + doc(f)["lights"][0]["position"].dump());
    const RenderResult res = r.render();
    EXPECT_EQ(res.stats.extra.at("host_waits").get<long long>(), 0) << "frame " << f;
    EXPECT_EQ(res.stats.extra.at("dispatches_by_pass").value("far field update", 0), 2);
    EXPECT_GT(res.stats.extra.at("far_field_terms").get<long long>(), 0);
    worst = std::max(worst,
                     compareImages(deviceImage(res), freshRender(doc(f), "gradient").image).relL2);
  }
  std::printf("far field updated in place against built whole: worst %.3g\n", worst);
  // Measured on llvmpipe 2026-12-07: 6.97e-9 (the grid's sums in another order); unmeasured on
  // hardware.
  EXPECT_LT(worst, unmeasuredOnHardware(6.97e-9));
}

/// The resident adaptive frame where the budget binds: levels [4, 8, 16] and the fallback on a
/// 40³ blob scene (2089 initial samples), Eq. 5's 6 probes (40 took this test 43 s in CI, 6 take
/// 9 s on llvmpipe): levels are capped and the top-up splits. Each steady frame's image, count
/// and levels' stats equal a fresh render's, with no host wait.
/// The top-up spends what the levels' shares left, whole groups of errors at a time, so whether
/// a budget tops up at all turns on E's last digits: on llvmpipe (2026-12-07) max_samples 2115,
/// 2140, 2145 and 2160 top up 1 split of level 2 in frame 0 (7 and 92 capped in levels 2 and 3 at
/// 2140), 2100, 2130 and 2175 none. The test takes the first budget of the list whose frame 0
/// tops up on this device, so that the top-up is exercised wherever it runs.
TEST(GpuSteadyFrame, AdaptiveUnderABindingBudgetAsAFreshRender) {
  SCATTERLAB_REQUIRE_GPU();
  int budget = 0;
  const auto doc = [&budget](int f) {
    Json d = blobSceneDoc(40, 32, 24);
    d["lights"][1]["position"] = {0.5 + 0.1 * f, 1.4, 0.5 - 0.05 * f};
    d["render"] = {{"method", "adaptive"},
                   {"levels", {4, 8, 16}},
                   {"max_samples", budget},
                   {"voxel_switch", 0},
                   {"probes", 6}};
    return d;
  };
  const auto toppedUpIn = [](const RenderResult& res) {
    long long n = 0;
    for (const Json& level : res.stats.extra.at("levels"))
      n += level.at("topped_up").get<long long>();
    return n;
  };
  std::vector<int> budgets = {2140, 2115, 2145, 2160};
  for (int b = 2100; b <= 2300; b += 5) budgets.push_back(b);
  for (const int b : budgets) {
    budget = b;
    if (toppedUpIn(freshRender(doc(0), "adaptive")) > 0) break;
    budget = 0;
  }
  ASSERT_GT(budget, 0) << "no budget from 2100 to 2300 tops up frame 0";
  std::printf("max_samples %d tops up\n", budget);
  Renderer r(doc(0), ".", "adaptive", "gpu");
  r.keepImageOnDevice(true);
  long long capped = 0, toppedUp = 0, lastCount = 0;
  for (int f = 0; f < 3; ++f) {
    if (f > 0) r.set("lights.1.position=" + doc(f)["lights"][1]["position"].dump());
    const RenderResult res = r.render();
    if (f > 0) {
      EXPECT_EQ(res.stats.extra.at("host_waits").get<long long>(), 0) << "frame " << f;
    }
    ASSERT_TRUE(res.deviceImage.has_value());
    const RenderResult fresh = freshRender(doc(f), "adaptive");
    ASSERT_TRUE(res.stats.samples.has_value());
    EXPECT_EQ(*res.stats.samples, *fresh.stats.samples) << "frame " << f;
    lastCount = *fresh.stats.samples;
    const Json& levels = fresh.stats.extra.at("levels");
    for (std::size_t l = 0; l < levels.size(); ++l) {
      for (const char* key : {"evaluated", "split", "capped", "topped_up", "kept"})
        EXPECT_EQ(res.stats.extra.at("levels")[l].at(key), levels[l].at(key))
            << key << " of level " << l << ", frame " << f;
      capped += levels[l].at("capped").get<long long>();
      toppedUp += levels[l].at("topped_up").get<long long>();
    }
    const double worst = compareImages(deviceImage(res), fresh.image).maxAbs;
    std::printf("frame %d: %lld samples, max |device image - fresh render| = %.3g\n", f,
                *res.stats.samples, worst);
    EXPECT_EQ(worst, 0.0) << "frame " << f;  // measured on llvmpipe: 0 (the same passes)
  }
  EXPECT_GT(capped, 0);
  EXPECT_GT(toppedUp, 0);
  // Nothing changed: the radiance volume is reused, and the count is its render's.
  const RenderResult again = r.render();
  EXPECT_TRUE(again.stats.extra.at("radiance_reused").get<bool>());
  ASSERT_TRUE(again.stats.samples.has_value());
  EXPECT_EQ(*again.stats.samples, lastCount);
}

INSTANTIATE_TEST_SUITE_P(Methods, GpuSteadyFrame,
                         ::testing::Values(std::make_tuple("gradient", true),
                                           std::make_tuple("gradient", false),
                                           std::make_tuple("per-voxel", false),
                                           std::make_tuple("adaptive", true),
                                           std::make_tuple("adaptive", false)),
                         [](const auto& info) {
                           std::string name = std::get<0>(info.param);
                           for (char& c : name)
                             if (c == '-') c = '_';
                           return name + (std::get<1>(info.param) ? "_paper" : "_defaults");
                         });

TEST(GpuSteadyFrame, UncoveredVoxelsAreFilledFromTheKeptListAsAFreshRenderSearches) {
  // Gaussian centres leave voxels at the plume's fringe that no sphere covers: a fresh render
  // searches their nearest samples, a steady frame (samples kept) writes them from the list the
  // first frame kept (gpu::NearestFill). The same image, the same count, no wait.
  SCATTERLAB_REQUIRE_GPU();
  std::ifstream in(SCATTERLAB_SOURCE_DIR "/data/scenes/fig3.json");
  const Json base = Json::parse(in);
  const auto doc = [&](int f) {
    Json d = base;
    d["medium"]["resolution"] = 32;
    d["camera"]["width"] = 40;
    d["camera"]["height"] = 30;
    d["render"] = {{"method", "gradient"},
                   {"paper", true},
                   {"sampler", {{"type", "gaussian-centres"}, {"count", 100}}}};
    d["lights"][0]["intensity"] = Json::array({1.0 + 0.2 * f, 1.0, 1.0 - 0.1 * f});
    return d;
  };
  initialize();
  const Scene cpuScene = parseScene(doc(0), SCATTERLAB_SOURCE_DIR "/data/scenes");
  const RenderResult cpu = createMethod(cpuScene, "", "cpu")->render(cpuScene, nullptr);
  const long long uncovered = cpu.stats.extra.at("uncovered_voxels").get<long long>();
  EXPECT_GT(uncovered, 0);
  Renderer r(doc(0), SCATTERLAB_SOURCE_DIR "/data/scenes", "", "gpu");
  for (int f = 0; f < 3; ++f) {
    if (f > 0) r.set("lights.0.intensity=" + doc(f)["lights"][0]["intensity"].dump());
    const RenderResult res = r.render();
    EXPECT_EQ(res.stats.extra.at("uncovered_voxels").get<long long>(), uncovered) << f;
    const Json& passes = res.stats.extra.at("gpu_ms");
    EXPECT_EQ(passes.contains("radiance nearest fill"), f > 0) << f;  // the kept list
    const Scene s = parseScene(doc(f), SCATTERLAB_SOURCE_DIR "/data/scenes");
    const Image fresh = createMethod(s, "", "gpu")->render(s, nullptr).image;
    EXPECT_EQ(compareImages(res.image, fresh).maxAbs, 0.0) << "frame " << f;
    if (f == 0) {
      // Measured on llvmpipe 2026-11-28: 3.42e-7; the end-to-end tests' bound (2.9e-6, from
      // an H200's 1.94e-6).
      const double toCpu = compareImages(res.image, cpu.image).relL2;
      std::printf("gaussian centres, gpu vs cpu: relative L2 %.3g\n", toCpu);
      EXPECT_LT(toCpu, 2.9e-6);
    }
  }
}

TEST(GpuSteadyFrame, ASpotWhoseConeWidensLeavesTheWholeSceneFallbackAndComesBack) {
  // Under spot lights only, the whole-scene fallback counts the occupied voxels a cone reaches,
  // from the lights every frame: a narrow cone switches to per-voxel V, a wide one does not.
  // A Renderer whose light widens and narrows again changes path from frame to frame, and each
  // frame is what a fresh render of its scene gives.
  SCATTERLAB_REQUIRE_GPU();
  const auto doc = [](float outerDeg) {
    Json d = homogeneousBoxDoc(1.0f, 1.5f, 0.8f, Vec3(0), 1.0f, 40, 30, 32);
    d["lights"] = Json::parse(R"([{"type": "spot", "position": [0.45, 1.4, 0.55],
        "direction": [0.1, -1, 0], "intensity": [3, 2.5, 2], "inner_deg": 4}])");
    d["lights"][0]["outer_deg"] = outerDeg;
    d["camera"]["position"] = {0.5, 0.6, -1.6};
    d["render"]["sampler"] = {{"type", "grid"}, {"count", 100}};
    d["render"]["voxel_switch"] = 2;
    return d;
  };
  initialize();
  Renderer r(doc(9.0f), ".", "adaptive", "gpu");
  r.keepImageOnDevice(true);
  const float cones[] = {9.0f, 40.0f, 9.0f};
  const bool switched[] = {true, false, true};
  for (int f = 0; f < 3; ++f) {
    if (f > 0) r.set("lights.0.outer_deg=" + std::to_string(cones[f]));
    const RenderResult res = r.render();
    EXPECT_EQ(res.stats.extra.at("voxels_instead").get<bool>(), switched[f]) << "frame " << f;
    ASSERT_TRUE(res.deviceImage.has_value());
    const Image fresh = freshRender(doc(cones[f]), "adaptive").image;
    double peak = 0.0;
    for (const Vec3& p : fresh.pixels())
      peak = std::max({peak, double(p.x), double(p.y), double(p.z)});
    EXPECT_GT(peak, 0.0) << "frame " << f;
    // The same passes as a fresh render.
    EXPECT_EQ(compareImages(deviceImage(res), fresh).maxAbs, 0.0) << "frame " << f;
  }
}

}  // namespace
}  // namespace scatterlab::testing

namespace scatterlab::testing {
namespace {

/// adaptive's and gradient's whole-scene fallback on the GPU (docs/fidelity.md): a sparse medium
/// (one small blob at 48³) is rendered as per-voxel renders it (the voxels holding V = S / A), on
/// the same rule as the CPU's and within the CPU's image; the decision is made once per density, so
/// a steady frame (a light moved) waits for nothing and equals a fresh render.
TEST(GpuSteadyFrame, ASparseMediumRenderedAsPerVoxelWaitsForNothing) {
  SCATTERLAB_REQUIRE_GPU();
  const auto doc = [](int f) {
    Json d =
        homogeneousBoxDoc(1.0f, 8.0f, 0.8f, Vec3(0.5f + 0.1f * f, 1.4f, 0.5f), 4.0f, 40, 30, 48);
    d["medium"]["density"] = {
        {"type", "gaussians"},
        {"blobs", Json::array({{{"center", {0.5, 0.5, 0.5}}, {"radius", 0.05}, {"weight", 1.0}}})}};
    return d;
  };
  initialize();
  for (const std::string method : {"adaptive", "gradient"}) {
    SCOPED_TRACE(method);
    const Scene cpuScene = parseScene(doc(0), ".");
    const RenderResult cpu = createMethod(cpuScene, method, "cpu")->render(cpuScene, nullptr);
    Renderer r(doc(0), ".", method, "gpu");
    r.keepImageOnDevice(true);
    for (int f = 0; f < 3; ++f) {
      if (f > 0) r.set("lights.0.position=" + doc(f)["lights"][0]["position"].dump());
      const RenderResult res = r.render();
      EXPECT_TRUE(res.stats.extra.at("voxels_instead").get<bool>()) << "frame " << f;
      EXPECT_EQ(res.stats.extra.at("occupied_voxels"), cpu.stats.extra.at("occupied_voxels"));
      if (f > 0) {
        EXPECT_EQ(res.stats.extra.at("host_waits").get<long long>(), 0) << "frame " << f;
      }
      ASSERT_TRUE(res.deviceImage.has_value());
      const Image fresh = freshRender(doc(f), method).image;
      if (f == 0) {
        const double toCpu = compareImages(fresh, cpu.image).relL2;
        std::printf("switched %s, gpu vs cpu: relative L2 %.3g\n", method.c_str(), toCpu);
        // Measured on llvmpipe: 1.94e-7 (2026-11-28), 2.05e-7 for both (2026-11-29); with
        // SCATTERLAB_GPU_IMPRECISE=2 / 4 (a GPU's approximate built-ins, 2026-12-07) 1.08e-6 /
        // 9.4e-7. Since the rays are the CPU's (cpu_arithmetic.glsl, 2026-12-08): 1.94e-7, N = 2
        // / 4 / 8 1.1e-7 / 1.86e-7 / 2.17e-7. Not measured on hardware: the hardware factor on
        // llvmpipe's figure (unmeasuredOnHardware, 8.1e-7; above N = 8's).
        EXPECT_LT(toCpu, unmeasuredOnHardware(1.94e-7));
      }
      // The same passes as a fresh render.
      EXPECT_EQ(compareImages(deviceImage(res), fresh).maxAbs, 0.0) << "frame " << f;
    }
  }
}

}  // namespace
}  // namespace scatterlab::testing
