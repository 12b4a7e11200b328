// Sum of Gaussians + residual hash: exact recovery, error falling with N on real smoke, the
// residual meeting 2%, mass kept by the diffused residual, the rendered smoke1 image within 3 %
// of the grid's, splatting equal to evaluation, and the .sog format checked on load.

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>

#include "api/scatterlab.h"
#include "media/dense_grid.h"
#include "media/sog.h"
#include "media/sog_fit.h"
#include "media/temp_dir.h"
#include "media/vdb.h"
#include "support/scenes.h"

namespace scatterlab {
namespace {

using testing::kVdb;

/// smoke1.vdb at half resolution (56x111x56), loaded once for the whole suite.
const DensityGrid& smokeHalf() {
  static const DensityGrid g = downsample(loadVdbAsDense(kVdb + "smoke1.vdb", "density"), 2);
  return g;
}

TEST(ResidualHash, InsertLookupGrow) {
  ResidualHash h(Box{}, IVec3(50, 50, 50), 16, 0.5f);
  for (std::uint32_t k = 0; k < 5000; ++k) h.insert(k * 17, std::int16_t(k % 300 + 1));
  EXPECT_EQ(h.size(), 5000u);
  for (std::uint32_t k = 0; k < 5000; ++k) ASSERT_EQ(h.code(k * 17), std::int16_t(k % 300 + 1));
  EXPECT_EQ(h.code(1), 0);
  EXPECT_EQ(h.code(17 * 5000), 0);
  const auto e = h.entries();
  ASSERT_EQ(e.size(), 5000u);
  EXPECT_TRUE(std::is_sorted(e.begin(), e.end()));
}

TEST(SogFit, RecoversExactSumOfGaussians) {
  const std::vector<GaussianBlob> truth = {{Vec3(0.30f, 0.35f, 0.40f), 0.10f, 1.0f},
                                           {Vec3(0.65f, 0.60f, 0.55f), 0.14f, 0.7f},
                                           {Vec3(0.45f, 0.70f, 0.30f), 0.07f, 1.3f},
                                           {Vec3(0.70f, 0.30f, 0.70f), 0.09f, 0.5f}};
  DensityGrid D(Box{Vec3(0), Vec3(1)}, IVec3(40));
  GaussianDensity(truth).build(D);
  SogFitOptions o;
  o.gaussians = 4;
  o.sweeps = 6;
  o.lmMaxEvaluations = 100;
  SogFitReport rep;
  const SogModel m = fitSog(D, o, &rep);
  EXPECT_EQ(rep.gaussians, 4);
  EXPECT_LT(rep.relL2Gaussians, 1e-3) << "D~ alone";
  EXPECT_LT(rep.relL2Model, 1e-3);
}

TEST(SogFit, SmokeErrorFallsWithGaussianCountAndResidualMeetsTwoPercent) {
  const DensityGrid& D = smokeHalf();
  double prev = 1e9;
  for (int n : {64, 256, 1024}) {
    SogFitOptions o;
    o.gaussians = n;
    o.fitVoxels = 28 * 28 * 28;
    o.sweeps = 1;
    o.log = [](const std::string& s) { std::printf("    %s\n", s.c_str()); };
    SogFitReport rep;
    const SogModel m = fitSog(D, o, &rep);
    EXPECT_LT(rep.relL2Gaussians, prev) << n << " Gaussians";
    prev = rep.relL2Gaussians;
    EXPECT_LT(rep.relL2Model, 0.02) << n << " Gaussians, default threshold";
    EXPECT_LT(rep.hashEntries, D.size()) << n;
    RecordProperty("relL2_" + std::to_string(n), std::to_string(rep.relL2Gaussians));
    std::printf("  N=%d (kept %d): D~ rel L2 %.4f, D~+F %.4f, %zu hash entries, %.2f s\n", n,
                rep.gaussians, rep.relL2Gaussians, rep.relL2Model, rep.hashEntries,
                rep.secondsTotal);
  }
}

/// A field built in code: one Gaussian of peak 1 (radius 0.12) plus a haze of 0.002 (below the
/// default threshold 0.003 · max D) filling the ball |x − (0.5, 0.5, 0.5)| < 0.4 on a 40³
/// lattice over the unit box. One fitted Gaussian captures the blob; the haze is residual.
DensityGrid blobInHaze(double& hazeMass, std::vector<char>& inHaze) {
  DensityGrid D(Box{Vec3(0), Vec3(1)}, IVec3(40));
  GaussianDensity({{Vec3(0.5f), 0.12f, 1.0f}}).build(D);
  hazeMass = 0;
  inHaze.assign(D.size(), 0);
  size_t idx = 0;
  for (int k = 0; k < 40; ++k)
    for (int j = 0; j < 40; ++j)
      for (int i = 0; i < 40; ++i, ++idx)
        if (glm::length(D.cellCenter(i, j, k) - Vec3(0.5f)) < 0.4f) {
          D.at(i, j, k) += 0.002f;
          hazeMass += 0.002;
          inHaze[idx] = 1;
        }
  return D;
}

TEST(SogFit, DiffusedResidualKeepsTheMassOfThinHaze) {
  double hazeMass = 0;
  std::vector<char> inHaze;
  const DensityGrid D = blobInHaze(hazeMass, inHaze);
  double massD = 0;
  for (float v : D.data()) massD += v;
  // Haze region (the ball minus the blob's core, where D < 0.01): there D = 0.002 + a small
  // Gaussian tail, so the model's mass there is compared with the input's.
  const auto regionMass = [&](const std::vector<float>& v) {
    double s = 0;
    for (size_t i = 0; i < v.size(); ++i)
      if (inHaze[i] && D.data()[i] < 0.01f) s += v[i];
    return s;
  };
  const double hazeIn = regionMass(D.data());
  EXPECT_GT(hazeIn, 0.9 * hazeMass);  // the haze dominates that region by construction
  for (SogResidualMode mode : {SogResidualMode::Diffuse, SogResidualMode::Drop}) {
    SogFitOptions o;
    o.gaussians = 1;
    o.sweeps = 4;
    o.residual = mode;
    SogFitReport rep;
    const SogModel m = fitSog(D, o, &rep);
    DensityGrid out(D.bounds(), D.dims());
    m.splat(out);
    double massM = 0;
    for (float v : out.data()) massM += v;
    const double hazeOut = regionMass(out.data());
    std::printf("  %s: total mass %+.5f%%, haze region %.4f of the input's, %zu entries\n",
                mode == SogResidualMode::Diffuse ? "diffuse" : "drop",
                100 * (massM - massD) / massD, hazeOut / hazeIn, rep.hashEntries);
    EXPECT_NEAR(rep.relMassModel, (massM - massD) / massD, 1e-9);
    if (mode == SogResidualMode::Diffuse) {
      // Error diffusion passes on exactly what a cell misses; only the carry left at the last
      // cell (and negative carry that cannot go below 0 in empty space) is lost.
      EXPECT_NEAR(massM, massD, 6.5e-6 * massD);  // measured −4.3e-6
      // Diffusion moves some haze across the region's edge: measured 0.9870.
      EXPECT_NEAR(hazeOut / hazeIn, 1.0, 0.02);
    } else {
      // Dropping |F| <= 0.003 removes the haze but the Gaussian tail inside it.
      EXPECT_LT(hazeOut / hazeIn, 0.56);  // measured 0.3723; total mass −3.94 %
    }
  }
}

/// Renders `scene` with `exact` on the CPU, with density `d`.
Image renderExact(Scene scene, std::shared_ptr<const DensityModel> d) {
  scene.medium.density = std::move(d);
  return createMethod(scene, "exact", "cpu")->render(scene, nullptr).image;
}

TEST(SogFit, Smoke1RenderedWithin3PercentOfTheGrid) {
  // Issue 11.6: 256 Gaussians at default settings, the smoke demo scene, exact.
  initialize();
  const DensityGrid D = loadVdbAsDense(kVdb + "smoke1.vdb", "density");
  const Scene smoke = loadScene(SCATTERLAB_SOURCE_DIR "/data/scenes/smoke.json");
  const Scene check = sogCheckScene(D);
  const Image gridSmoke = renderExact(smoke, std::make_shared<DenseGridDensity>(D, "smoke1"));
  const Image gridCheck = renderExact(check, check.medium.density);
  double err[2][2];
  for (SogResidualMode mode : {SogResidualMode::Diffuse, SogResidualMode::Drop}) {
    SogFitOptions o;
    o.gaussians = 256;
    o.residual = mode;
    const auto m = std::make_shared<SogDensity>(fitSog(D, o), "fit");
    const int r = mode == SogResidualMode::Drop;
    err[r][0] = compareImages(renderExact(smoke, m), gridSmoke).relL2;
    err[r][1] = compareImages(renderExact(check, m), gridCheck).relL2;
    std::printf("  %s: smoke.json %.4f, fit's check view %.4f\n", r ? "drop" : "diffuse", err[r][0],
                err[r][1]);
  }
  // Issue bound 3 %; measured 0.0152 and 0.0158 (tolerance ×1.5).
  EXPECT_LT(err[0][0], 0.023) << "smoke.json, diffused residual (default)";
  EXPECT_LT(err[0][1], 0.024) << "fit's check view, diffused residual (default)";
  // The old fit (dropped residual) fails the 3 % bound, measured 0.0464 and 0.0793: what the
  // check exists to catch.
  EXPECT_GT(err[1][0], 0.03) << "smoke.json, dropped residual";
  EXPECT_GT(err[1][1], 0.03) << "fit's check view, dropped residual";
}

SogModel smallModel() {
  SogModel m;
  m.gaussians = {{Vec3(0.3f, 0.4f, 0.5f), 0.12f, 1.0f},
                 {Vec3(0.6f, 0.5f, 0.4f), 0.2f, 0.6f},
                 {Vec3(0.9f, 0.9f, 0.9f), 0.05f, 2.0f}};
  m.residual = ResidualHash(Box{Vec3(0), Vec3(1)}, IVec3(10, 12, 8), 8, 0.01f);
  m.residual.insert(0, 5);
  m.residual.insert(123, -40);
  m.residual.insert(500, 127);
  m.residual.insert(10 * 12 * 8 - 1, -128);
  m.threshold = 0.02f;
  return m;
}

TEST(SogModel, SplattingEqualsEvaluationAtCellCentres) {
  const SogModel m = smallModel();
  for (IVec3 dims : {IVec3(32), IVec3(17, 23, 9)}) {
    for (const Box& box : {Box{Vec3(0), Vec3(1)}, Box{Vec3(-0.2f), Vec3(1.1f, 0.8f, 1.3f)}}) {
      DensityGrid g(box, dims);
      m.splat(g);
      for (int k = 0; k < dims.z; ++k)
        for (int j = 0; j < dims.y; ++j)
          for (int i = 0; i < dims.x; ++i)
            ASSERT_NEAR(g.at(i, j, k), m.eval(g.cellCenter(i, j, k)), 1e-6f)
                << i << " " << j << " " << k;
    }
  }
}

TEST(SogModel, SplattingEqualsEvaluationForFittedSmoke) {
  SogFitOptions o;
  o.gaussians = 64;
  o.fitVoxels = 20 * 20 * 20;
  o.sweeps = 0;
  const SogModel m = fitSog(smokeHalf(), o);
  const SogDensity d(m, "test");
  DensityGrid g(*d.naturalBounds(), IVec3(24, 40, 24));
  d.build(g);
  double maxErr = 0;
  for (int k = 0; k < 24; ++k)
    for (int j = 0; j < 40; ++j)
      for (int i = 0; i < 24; ++i)
        maxErr = std::max(maxErr, double(std::abs(g.at(i, j, k) - d.eval(g.cellCenter(i, j, k)))));
  EXPECT_LT(maxErr, 1e-5);
}

TEST(SogModel, ResidualIsExactAtLatticeCentres) {
  const SogModel m = smallModel();
  const ResidualHash& h = m.residual;
  DensityGrid lattice(h.bounds(), h.dims());
  EXPECT_FLOAT_EQ(h.sample(lattice.cellCenter(3, 0, 1)), -0.4f);  // key 123 = 3 + 10*(0 + 12*1)
  EXPECT_FLOAT_EQ(h.sample(lattice.cellCenter(0, 2, 4)), 1.27f);  // key 500 = 0 + 10*(2 + 12*4)
  EXPECT_FLOAT_EQ(h.sample(lattice.cellCenter(0, 0, 0)), 0.05f);
  EXPECT_EQ(h.sample(Vec3(2.0f)), 0.0f);
}

TEST(SogFile, RoundTrip) {
  testing::TempDir tmp("sog");
  const SogModel m = smallModel();
  const std::string p = tmp.file("m.sog");
  writeSog(p, m);
  EXPECT_EQ(std::filesystem::file_size(p), m.fileBytes());
  const SogModel r = readSog(p);
  ASSERT_EQ(r.gaussians.size(), m.gaussians.size());
  EXPECT_EQ(r.residual.entries(), m.residual.entries());
  EXPECT_EQ(r.residual.dims(), m.residual.dims());
  EXPECT_FLOAT_EQ(r.residual.step(), m.residual.step());
  for (float x = 0.05f; x < 1; x += 0.1f)
    EXPECT_FLOAT_EQ(r.eval(Vec3(x, 0.5f, x)), m.eval(Vec3(x, 0.5f, x)));
}

TEST(SogFile, SixteenBitRoundTrip) {
  testing::TempDir tmp("sog");
  SogModel m = smallModel();
  m.residual = ResidualHash(Box{Vec3(0), Vec3(1)}, IVec3(4), 16, 1e-4f);
  m.residual.insert(7, -30000);
  const std::string p = tmp.file("m16.sog");
  writeSog(p, m);
  EXPECT_EQ(readSog(p).residual.code(7), -30000);
}

std::string ioMessage(const std::string& p) {
  try {
    readSog(p);
  } catch (const IoError& e) {
    return e.what();
  }
  ADD_FAILURE() << "no IoError for " << p;
  return "";
}

TEST(SogFile, TruncatedForeignCorruptAreIoErrors) {
  testing::TempDir tmp("sog");
  const std::string good = tmp.file("good.sog");
  writeSog(good, smallModel());
  std::ifstream in(good, std::ios::binary);
  const std::string all((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  for (size_t keep = 0; keep < all.size(); keep += 7) {
    const std::string p = tmp.file("cut.sog");
    std::ofstream(p, std::ios::binary | std::ios::trunc).write(all.data(), std::streamsize(keep));
    const std::string m = ioMessage(p);
    EXPECT_NE(m.find(p), std::string::npos) << m;
  }
  const std::string cut = tmp.file("cut100.sog");
  std::ofstream(cut, std::ios::binary).write(all.data(), 100);
  EXPECT_NE(ioMessage(cut).find("truncated"), std::string::npos) << ioMessage(cut);
  const std::string foreign = tmp.file("foreign.sog");
  std::filesystem::copy_file(kVdb + "dragon_with_xform.vdb.txt", foreign);
  EXPECT_NE(ioMessage(foreign).find("signature"), std::string::npos);
  std::string flipped = all;
  flipped[80] ^= 0x10;
  const std::string corrupt = tmp.file("corrupt.sog");
  std::ofstream(corrupt, std::ios::binary).write(flipped.data(), std::streamsize(flipped.size()));
  EXPECT_NE(ioMessage(corrupt).find("checksum"), std::string::npos) << ioMessage(corrupt);
  std::string v2 = all;
  v2[8] = 2;
  const std::string future = tmp.file("v2.sog");
  std::ofstream(future, std::ios::binary).write(v2.data(), std::streamsize(v2.size()));
  EXPECT_NE(ioMessage(future).find("version 2"), std::string::npos) << ioMessage(future);
  EXPECT_NE(ioMessage(tmp.file("missing.sog")).find("missing.sog"), std::string::npos);
}

TEST(SogScene, LoadsFileAndFrames) {
  testing::TempDir tmp("sog");
  SogModel a = smallModel(), b = smallModel();
  b.gaussians.resize(1);
  writeSog(tmp.file("f0.sog"), a);
  writeSog(tmp.file("f1.sog"), b);
  const auto doc = [&](Json density) {
    return Json{
        {"medium", {{"density", density}, {"resolution", 8}}},
        {"lights", Json::array({{{"type", "point"}, {"position", {0, 0, 0}}, {"intensity", 1}}})},
        {"camera", {{"position", {0.5, 0.5, -3}}, {"look_at", {0.5, 0.5, 0.5}}}}};
  };
  const Scene s = testing::sceneFromJson(doc({{"type", "sog"}, {"file", tmp.file("f0.sog")}}));
  EXPECT_EQ(s.medium.bounds.max, Vec3(1));
  EXPECT_NE(s.medium.density->describe().find("3 Gaussians"), std::string::npos);
  const Scene s1 = testing::sceneFromJson(doc({{"type", "sog"},
                                               {"frames", {tmp.file("f0.sog"), tmp.file("f1.sog")}},
                                               {"time", 0.5},
                                               {"fps", 2}}));
  EXPECT_NE(s1.medium.density->describe().find("1 Gaussians"), std::string::npos)
      << s1.medium.density->describe();
  EXPECT_THROW(testing::sceneFromJson(doc({{"type", "sog"}})), ConfigError);
  EXPECT_THROW(testing::sceneFromJson(doc({{"type", "sog"}, {"frames", {1}}})), ConfigError);
  EXPECT_THROW(testing::sceneFromJson(doc({{"type", "sog"}, {"file", tmp.file("nope.sog")}})),
               IoError);
}

TEST(SogDensity, GaussianCentresAreTheInitialSamplesOfGradient) {
  testing::TempDir tmp("sogsamples");
  const std::string file = tmp.file("m.sog");
  writeSog(file, smallModel());
  Json doc = testing::homogeneousBoxDoc(1.0f, 1.2f, 0.6f, Vec3(0.5f, 1.3f, 0.5f), 2.0f, 16, 12, 16);
  doc["medium"]["density"] = {{"type", "sog"}, {"file", file}};
  // The paper's default sampler (the extensions default to jittered samples).
  doc["render"] = {{"method", "gradient"}, {"paper", true}};
  const Scene scene = testing::sceneFromJson(doc);
  ASSERT_NE(scene.medium.density->gaussians(), nullptr);
  EXPECT_EQ(scene.medium.density->gaussians()->size(), 3u);
  const RenderResult r = createMethod(scene)->render(scene, nullptr);
  EXPECT_EQ(r.stats.extra["sampler"], "gaussian-centres");
  ASSERT_EQ(r.samples.size(), 3u);
  EXPECT_EQ(r.samples[1].position, Vec3(0.6f, 0.5f, 0.4f));
  EXPECT_FLOAT_EQ(r.samples[1].radius, 3.0f * 0.2f);
}

}  // namespace
}  // namespace scatterlab
