#include <gtest/gtest.h>

#include "core/camera.h"
#include "core/light.h"
#include "core/phase.h"

using namespace scatterlab;

namespace {

/// ∫ f(cosθ) g(cosθ) dω over the sphere = 2π ∫_{-1}^{1} f(μ) g(μ) dμ, by composite Simpson in
/// double with many intervals (the HG peak for g = 0.9 has width ~(1−g)).
template <class F>
double sphereIntegral(F f, int n = 200000) {
  const double h = 2.0 / n;
  double s = f(-1.0) + f(1.0);
  for (int i = 1; i < n; ++i) s += (i % 2 ? 4.0 : 2.0) * f(-1.0 + i * h);
  return 2.0 * 3.14159265358979323846 * s * h / 3.0;
}

}  // namespace

TEST(Phase, IsotropicIsOneOverFourPi) {
  Phase p;
  EXPECT_FLOAT_EQ(p.evalCos(0.3f), 1.0f / (4.0f * kPi));
  EXPECT_NEAR(sphereIntegral([&](double mu) { return p.evalCos(float(mu)); }), 1.0, 1e-6);
}

class HgTest : public ::testing::TestWithParam<float> {};

TEST_P(HgTest, IntegratesToOneAndMeanCosineIsG) {
  Phase p{Phase::Type::HenyeyGreenstein, GetParam()};
  const double norm = sphereIntegral([&](double mu) { return double(p.evalCos(float(mu))); });
  const double meanCos =
      sphereIntegral([&](double mu) { return mu * double(p.evalCos(float(mu))); });
  EXPECT_NEAR(norm, 1.0, 1e-4);
  EXPECT_NEAR(meanCos, GetParam(), 1e-4);
}

INSTANTIATE_TEST_SUITE_P(Asymmetries, HgTest, ::testing::Values(-0.7f, -0.2f, 0.0f, 0.3f, 0.9f));

TEST(Phase, HgPositiveGScattersForward) {
  // Light travelling +z, continuing towards a viewer further along +z: no deflection.
  Phase p{Phase::Type::HenyeyGreenstein, 0.6f};
  const Vec3 lightDir(0, 0, 1);
  EXPECT_GT(p.eval(lightDir, Vec3(0, 0, 1)), 10.0f * p.eval(lightDir, Vec3(0, 0, -1)));
}

TEST(Camera, RowZeroIsAtTheTopAndCentreLooksAtTarget) {
  Camera c;
  c.position = Vec3(0, 0, 0);
  c.lookAt = Vec3(0, 0, 5);
  c.width = 4;
  c.height = 2;
  c.fovYDeg = 90;
  const Ray top = c.primaryRay(1, 0), bottom = c.primaryRay(1, 1);
  EXPECT_GT(top.dir.y, 0.0f);
  EXPECT_LT(bottom.dir.y, 0.0f);
  // Pixel (1,0) centre at NDC x = (1.5/4)*2-1 = -0.25, y = 0.5; fov 90 → tan = 1, aspect 2.
  const Vec3 expected = glm::normalize(Vec3(-(-0.25f * 2.0f), 0.5f, 1.0f));
  // Right-handed: with up = +y and forward = +z, right = forward × up = -x.
  EXPECT_NEAR(top.dir.x, expected.x, 1e-6);
  EXPECT_NEAR(top.dir.y, expected.y, 1e-6);
  EXPECT_NEAR(top.dir.z, expected.z, 1e-6);
}

TEST(Camera, ProjectInvertsPrimaryRay) {
  Camera c;
  c.width = 64;
  c.height = 48;
  for (int py : {0, 17, 47})
    for (int px : {0, 31, 63}) {
      const Ray r = c.primaryRay(px, py);
      float x, y;
      ASSERT_TRUE(c.project(r.at(3.0f), x, y));
      EXPECT_NEAR(x, px + 0.5f, 1e-3);
      EXPECT_NEAR(y, py + 0.5f, 1e-3);
    }
}

TEST(Light, PointIrradianceFallsWithInverseSquare) {
  Light l;
  l.position = Vec3(0, 0, 0);
  l.intensity = Vec3(4, 8, 12);
  Light::Incident inc;
  ASSERT_TRUE(l.incident(Vec3(0, 2, 0), inc));
  EXPECT_FLOAT_EQ(inc.distance, 2.0f);
  EXPECT_FLOAT_EQ(inc.irradiance.x, 1.0f);
  EXPECT_FLOAT_EQ(inc.irradiance.z, 3.0f);
  EXPECT_FLOAT_EQ(inc.toLight.y, -1.0f);
}

TEST(Light, SpotFalloffIsOneInsideZeroOutsideSmoothBetween) {
  Light l;
  l.type = Light::Type::Spot;
  l.position = Vec3(0);
  l.direction = Vec3(0, -1, 0);
  l.cosInner = std::cos(10.0f * kPi / 180.0f);
  l.cosOuter = std::cos(20.0f * kPi / 180.0f);
  const auto at = [&](float deg) {
    const float a = deg * kPi / 180.0f;
    return l.spotFalloff(Vec3(std::sin(a), -std::cos(a), 0));
  };
  EXPECT_FLOAT_EQ(at(0), 1.0f);
  EXPECT_FLOAT_EQ(at(9.9f), 1.0f);
  EXPECT_FLOAT_EQ(at(20.1f), 0.0f);
  EXPECT_FLOAT_EQ(at(90), 0.0f);
  float prev = 1.0f;
  for (float d = 10.0f; d <= 20.0f; d += 0.5f) {
    EXPECT_LE(at(d), prev + 1e-6f);
    prev = at(d);
  }
  EXPECT_GT(at(15), 0.2f);
  EXPECT_LT(at(15), 0.8f);
  Light::Incident inc;
  EXPECT_FALSE(l.incident(Vec3(0, 1, 0), inc));  // behind the spot
}

TEST(Light, DirectionalIsConstant) {
  Light l;
  l.type = Light::Type::Directional;
  l.direction = Vec3(0, -1, 0);
  l.intensity = Vec3(2);
  Light::Incident inc;
  ASSERT_TRUE(l.incident(Vec3(5, 3, 1), inc));
  EXPECT_EQ(inc.toLight, Vec3(0, 1, 0));
  EXPECT_EQ(inc.irradiance, Vec3(2));
  EXPECT_TRUE(std::isinf(inc.distance));
}
