// Compositing outputs (issue 15): the alpha every integrator records is 1 − the view ray's
// transmittance, so fog rendered over black plus (1 − A)·plate equals the fog rendered in front
// of the plate; the EXR carries A and the render's provenance.
#include <gtest/gtest.h>

#include <OpenEXR/ImfInputFile.h>
#include <OpenEXR/ImfStandardAttributes.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <iterator>

#include "api/scatterlab.h"
#ifdef SCATTERLAB_HAS_GPU
#include "gpu/context.h"
#endif
#include "support/scenes.h"

namespace scatterlab {
namespace {

/// Unit box of density 0.8, σt = 2, a point light above; 33×25 pixels so that the centre
/// pixel's ray runs along +z through the box centre (path length exactly 1).
Json boxDoc(Vec3 background) {
  Json doc = testing::homogeneousBoxDoc(0.8f, 2.0f, 0.7f, Vec3(0.5f, 1.3f, 0.5f), 3.0f, 33, 25, 16);
  doc["background"] = {background.x, background.y, background.z};
  return doc;
}

Image render(const Json& doc, const std::string& method, const std::string& backend) {
  const Scene s = testing::sceneFromJson(doc);
  return createMethod(s, method, backend)->render(s, nullptr).image;
}

/// max over pixels and channels of |black + (1 − A)·plate − over| / max(1, |over|).
double compositeError(const Image& black, const Image& over, Vec3 plate) {
  EXPECT_EQ(black.alpha().size(), black.pixels().size());
  double worst = 0.0;
  for (size_t i = 0; i < black.pixels().size(); ++i) {
    const Vec3 c = black.pixels()[i] + (1.0f - black.alpha()[i]) * plate;
    for (int k = 0; k < 3; ++k)
      worst = std::max(worst, double(std::abs(c[k] - over.pixels()[i][k])) /
                                  std::max(1.0, double(std::abs(over.pixels()[i][k]))));
  }
  return worst;
}

TEST(Compositing, AlphaIsOneMinusTransmittanceOfExact) {
  const Image img = render(boxDoc(Vec3(0.0f)), "exact", "cpu");
  // Beer–Lambert along the centre ray: T = exp(−σt·D·1).
  const float alpha = img.alpha()[size_t(12) * 33 + 16];
  // Measured 3.0e-8 (float exp per step; constant density, so the steps are exact).
  EXPECT_NEAR(alpha, 1.0 - std::exp(-2.0 * 0.8), 5e-8);
  // A corner ray misses the box: nothing in front of the plate.
  EXPECT_EQ(img.alpha()[0], 0.0f);
}

/// Z: the camera-space depth of the expected first interaction. Along the centre ray the box
/// is entered at depth 2 and is 1 deep, κ = σt·D = 1.6, so E[t | interaction] = 2 + 1/κ −
/// e^(−κ)/(1 − e^(−κ)) = 2.372036 (the density of the first interaction is κ·e^(−κs) on [0, 1]).
TEST(Compositing, DepthIsTheExpectedFirstInteraction) {
  const double kappa = 2.0 * 0.8;
  const double expected = 2.0 + 1.0 / kappa - std::exp(-kappa) / (1.0 - std::exp(-kappa));
  for (const char* method : {"exact", "gradient"}) {
    SCOPED_TRACE(method);
    const Image img = render(boxDoc(Vec3(0.0f)), method, "cpu");
    ASSERT_EQ(img.depth().size(), img.pixels().size());
    const float z = img.depth()[size_t(12) * 33 + 16];
    // Measured 5.21e-4 for both (2.3725502: the midpoint sum over 16 steps of 1/16).
    EXPECT_NEAR(z, expected, 7.8e-4);
    // A corner ray meets nothing: no depth.
    EXPECT_TRUE(std::isinf(img.depth()[0]));
  }
  // The EXR's Z channel carries it unchanged.
  const Image img = render(boxDoc(Vec3(0.0f)), "exact", "cpu");
  const std::string path =
      (std::filesystem::temp_directory_path() / "scatterlab_test_depth.exr").string();
  writeExr(img, path);
  const Image back = readExr(path);
  std::filesystem::remove(path);
  ASSERT_EQ(back.depth().size(), img.depth().size());
  for (size_t i = 0; i < img.depth().size(); ++i) EXPECT_EQ(back.depth()[i], img.depth()[i]) << i;
}

TEST(Compositing, FogOverAPlateCpu) {
  const Vec3 plate(0.3f, 0.5f, 0.7f);
  for (const char* method : {"exact", "per-voxel", "gradient"}) {
    SCOPED_TRACE(method);
    const Image black = render(boxDoc(Vec3(0.0f)), method, "cpu");
    const Image over = render(boxDoc(plate), method, "cpu");
    // Measured 6.0e-8 for each (float rounding of L + T·plate against L + (1 − (1 − T))·plate).
    EXPECT_LT(compositeError(black, over, plate), 1e-7);
  }
}

TEST(Compositing, FogOverAPlateGpu) {
#ifdef SCATTERLAB_HAS_GPU
  std::string why;
  if (!gpu::tryContext(&why)) GTEST_SKIP() << why;
  const Vec3 plate(0.3f, 0.5f, 0.7f);
  const Image black = render(boxDoc(Vec3(0.0f)), "gradient", "gpu");
  const Image over = render(boxDoc(plate), "gradient", "gpu");
  // Measured 1.8e-7 on llvmpipe (the blend unit's float arithmetic).
  EXPECT_LT(compositeError(black, over, plate), 3e-7);
  // The slice marcher's transmittance agrees with the CPU marcher's (centre pixel): measured
  // equal to 1e-8 on llvmpipe; 1e-5 leaves room for a hardware GPU's exp.
  const Image cpu = render(boxDoc(Vec3(0.0f)), "gradient", "cpu");
  EXPECT_NEAR(black.alpha()[size_t(12) * 33 + 16], cpu.alpha()[size_t(12) * 33 + 16], 1e-5);
#else
  GTEST_SKIP() << "built without the GPU backend";
#endif
}

TEST(Compositing, ExrCarriesAlphaAndAttributes) {
  const Image img = render(boxDoc(Vec3(0.0f)), "exact", "cpu");
  const std::string path = ::testing::TempDir() + "/compositing_alpha.exr";
  ExrAttributes attrs;
  attrs.strings = {{"scatterlab:method", "exact"}};
  attrs.matrices = {{"worldToCamera", {1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1}}};
  writeExr(img, path, attrs);
  const Image back = readExr(path);
  ASSERT_EQ(back.alpha().size(), img.alpha().size());
  for (size_t i = 0; i < img.alpha().size(); ++i) ASSERT_EQ(back.alpha()[i], img.alpha()[i]);
  std::ifstream f(path, std::ios::binary);
  const std::string bytes((std::istreambuf_iterator<char>(f)), {});
  EXPECT_NE(bytes.find("scatterlab:method"), std::string::npos);
  EXPECT_NE(bytes.find("worldToCamera"), std::string::npos);
  EXPECT_NE(bytes.find("m44f"), std::string::npos);
  // The colour space (issue 25): linear Rec. 709 primaries, D65 white, as OpenEXR reads it.
  Imf::InputFile in(path.c_str());
  ASSERT_TRUE(Imf::hasChromaticities(in.header()));
  const Imf::Chromaticities c = Imf::chromaticities(in.header());
  EXPECT_EQ(c.red, Imath::V2f(0.64f, 0.33f));
  EXPECT_EQ(c.green, Imath::V2f(0.30f, 0.60f));
  EXPECT_EQ(c.blue, Imath::V2f(0.15f, 0.06f));
  EXPECT_EQ(c.white, Imath::V2f(0.3127f, 0.3290f));
  std::filesystem::remove(path);
}

}  // namespace
}  // namespace scatterlab
