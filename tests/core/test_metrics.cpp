// Image metrics (core/metrics.h, docs/metrics.md) on small hand-made images whose answers are
// known exactly: visibly wrong share, PSNR, and the light mask with the masked relative L2.

#include <gtest/gtest.h>

#include <cmath>

#include "core/error.h"
#include "core/metrics.h"

namespace scatterlab {
namespace {

Image filled(int w, int h, Vec3 v) {
  Image img(w, h);
  for (Vec3& p : img.pixels()) p = v;
  return img;
}

TEST(Metrics, VisiblyWrongUsesThePngTransform) {
  // Grey 0.5 encodes to 0.73536. 0.56 encodes 0.0382 higher (not visible), 0.6 0.0624 higher
  // (visible); 2 vs 5 differ by 3 in linear units but both clamp to white (not visible).
  Image ref = filled(4, 1, Vec3(0.5f)), img = ref;
  ref.at(3, 0) = Vec3(2.0f);
  img.at(1, 0).y = 0.56f;
  img.at(2, 0).z = 0.6f;
  img.at(3, 0) = Vec3(5.0f);
  const ImageError e = compareImages(img, ref);
  EXPECT_DOUBLE_EQ(e.visiblyWrong, 0.25);
  EXPECT_NEAR(e.maxAbs, 3.0, 1e-7);
  EXPECT_TRUE(std::isnan(e.maskedRelL2));  // no mask given
  EXPECT_DOUBLE_EQ(compareImages(ref, ref).visiblyWrong, 0.0);
  // Black against white in every pixel: all wrong.
  EXPECT_DOUBLE_EQ(compareImages(filled(3, 2, Vec3(0)), filled(3, 2, Vec3(1))).visiblyWrong, 1.0);
}

TEST(Metrics, PsnrIsOnTheToneMappedImage) {
  // One of two pixels white instead of black: MSE over 6 channel values = 3/6 -> 10·log10(2).
  Image ref = filled(2, 1, Vec3(0)), img = ref;
  img.at(0, 0) = Vec3(1.0f);
  EXPECT_NEAR(compareImages(img, ref).psnr, 10.0 * std::log10(2.0), 1e-12);
  // Brighter than white changes nothing after the clamp.
  img.at(0, 0) = Vec3(7.0f);
  EXPECT_NEAR(compareImages(img, ref).psnr, 10.0 * std::log10(2.0), 1e-12);
}

/// An 8×8 camera looking down +Z at (0.5, 0.5, 0.5), with `lights`.
Scene cameraScene(std::vector<Light> lights) {
  Scene s;
  s.camera.position = Vec3(0.5f, 0.5f, -2.0f);
  s.camera.lookAt = Vec3(0.5f);
  s.camera.width = 8;
  s.camera.height = 8;
  s.lights = std::move(lights);
  return s;
}

Light pointAt(Vec3 p) {
  Light l;
  l.position = p;
  return l;
}

TEST(Metrics, MaskedRelativeL2ExcludesTheDiscAroundTheLight) {
  // The light projects onto the image centre (4, 4), a pixel corner; radius 1 keeps exactly
  // the four pixel centres at distance √0.5 (the next ones are at √2.5 > 1).
  const Scene s = cameraScene({pointAt(Vec3(0.5f))});
  const LightMask m = lightMask(s, 1.0);
  EXPECT_EQ(m.lights, 1);
  ASSERT_EQ(m.maskedPixels(), 4u);
  for (int y = 3; y <= 4; ++y)
    for (int x = 3; x <= 4; ++x) EXPECT_EQ(m.px[y * 8 + x], 1) << x << "," << y;
  // Reference 1 everywhere; the image is 11 on the four masked pixels (a glow's error) and 2
  // on one far pixel.
  const Image ref = filled(8, 8, Vec3(1));
  Image img = ref;
  for (int y = 3; y <= 4; ++y)
    for (int x = 3; x <= 4; ++x) img.at(x, y) = Vec3(11);
  img.at(0, 7) = Vec3(2);
  const ImageError e = compareImages(img, ref, m);
  EXPECT_NEAR(e.relL2, std::sqrt(401.0 / 64.0), 1e-12);
  EXPECT_NEAR(e.maskedRelL2, std::sqrt(1.0 / 60.0), 1e-12);
  EXPECT_DOUBLE_EQ(e.maskRadius, 1.0);
  EXPECT_EQ(e.maskedLights, 1);
  // A radius of 1.6 reaches the 8 edge neighbours at √2.5 ≈ 1.58 but not the corners (√4.5).
  EXPECT_EQ(lightMask(s, 1.6).maskedPixels(), 12u);
  // A mask that keeps nothing gives NaN, not a number.
  EXPECT_TRUE(std::isnan(compareImages(img, ref, lightMask(s, 100.0)).maskedRelL2));
}

TEST(Metrics, LightsBehindOffImageOrDirectionalMaskNothing) {
  Light sun;
  sun.type = Light::Type::Directional;
  Light spot = pointAt(Vec3(0.5f, 0.5f, -3.0f));  // behind the camera
  spot.type = Light::Type::Spot;
  const Scene s =
      cameraScene({pointAt(Vec3(0.5f, 0.5f, -3.0f)), pointAt(Vec3(100, 0.5f, 0.5f)), sun, spot});
  const LightMask m = lightMask(s, 3.0);
  EXPECT_EQ(m.lights, 0);
  EXPECT_EQ(m.maskedPixels(), 0u);
  Image ref = filled(8, 8, Vec3(1)), img = ref;
  img.at(2, 5) = Vec3(3);
  const ImageError e = compareImages(img, ref, m);
  EXPECT_DOUBLE_EQ(e.maskedRelL2, e.relL2);
  EXPECT_NEAR(e.relL2, std::sqrt(4.0 / 64.0), 1e-12);
  // A spot light in front of the camera is masked like a point light.
  Light front = spot;
  front.position = Vec3(0.5f);
  EXPECT_EQ(lightMask(cameraScene({front}), 1.0).maskedPixels(), 4u);
}

TEST(Metrics, DefaultRadiusAndSizeChecks) {
  EXPECT_DOUBLE_EQ(defaultMaskRadius(320, 240), 4.0);  // 1% of the 400-px diagonal
  EXPECT_DOUBLE_EQ(defaultMaskRadius(16, 12), 2.0);    // 0.2 px, raised to the 2-px floor
  const LightMask m = lightMask(cameraScene({}), 2.0);
  EXPECT_THROW(compareImages(Image(8, 4), Image(8, 4), m), ConfigError);
  EXPECT_THROW(compareImages(Image(8, 8), Image(8, 4), m), ConfigError);
}

}  // namespace
}  // namespace scatterlab
