/// The real-time methods beside the paper's (issue 13): light-space-march (Tóth & Umenhoffer
/// 2009) and radial-blur (Mitchell, GPU Gems 3 ch. 13), CPU variants — their defining
/// properties, their convergence to `exact`, their shadow maps, and their errors.

#include <gtest/gtest.h>

#include "core/method.h"
#include "core/metrics.h"
#include "cpu/light_space_march.h"
#include "cpu/radial_blur.h"
#include "cpu/ray_marcher.h"
#include "support/scenes.h"

using namespace scatterlab;
using scatterlab::testing::homogeneousBoxDoc;
using scatterlab::testing::relL2;
using scatterlab::testing::sceneFromJson;

namespace {

/// Homogeneous fog in the unit box lit by a spot light from above (inner 20°, outer 30°).
Json spotFogDoc(int width, int height) {
  Json doc = homogeneousBoxDoc(1.0f, 2.0f, 0.8f, Vec3(0.5f, 1.5f, 0.5f), 4.0f, width, height, 16);
  doc["lights"][0] = {{"type", "spot"},          {"position", {0.5, 1.5, 0.5}},
                      {"direction", {0, -1, 0}}, {"intensity", {4, 4, 4}},
                      {"inner_deg", 20},         {"outer_deg", 30}};
  doc["medium"]["phase"] = {{"type", "henyey-greenstein"}, {"g", 0.4}};
  return doc;
}

/// Two Gaussian blobs (inhomogeneous) with a point light between them.
/// blobDoc with its light behind the box (z = 1.4, in view): radial-blur's scene (it refuses a
/// light inside the medium).
Json blurDoc(int width, int height);

Json blobDoc(int width, int height) {
  Json doc = homogeneousBoxDoc(1.0f, 3.0f, 0.7f, Vec3(0.55f, 0.6f, 0.45f), 2.0f, width, height, 24);
  doc["medium"]["density"] = {
      {"type", "gaussians"},
      {"blobs", Json::array({{{"center", {0.4, 0.5, 0.5}}, {"radius", 0.2}, {"weight", 1.0}},
                             {{"center", {0.7, 0.4, 0.6}}, {"radius", 0.15}, {"weight", 0.8}}})}};
  return doc;
}

Json blurDoc(int width, int height) {
  Json doc = blobDoc(width, height);
  doc["lights"][0]["position"] = {0.55, 0.6, 1.4};
  return doc;
}

LightSpaceMarchSettings lsm(int steps, int interleave, LightTransmittance light) {
  LightSpaceMarchSettings s;
  s.steps = steps;
  s.interleave = interleave;
  s.light = light;
  return s;
}

Image renderMethod(Scene s, const Json& render) {
  s.render = render;
  return createMethod(s, "", "cpu")->render(s, nullptr).image;
}

/// The ConfigError message of creating (and rendering) `method` with `render` on `scene`.
std::string errorOf(Scene s, const Json& render) {
  s.render = render;
  try {
    auto m = createMethod(s, "", "cpu");
    m->render(s, nullptr);
  } catch (const ConfigError& e) {
    return e.what();
  }
  return "";
}

// ------------------------------------------------------------------ light-space-march

TEST(LightSpaceMarch, InterleaveOneIsThePlainMarch) {
  const Scene s = sceneFromJson(blobDoc(24, 18));
  const DensityGrid d = buildDensityVolume(s);
  const LightSpaceMarcher plain(s, d, lsm(32, 1, LightTransmittance::Mean), s.medium.voxelSize());
  const Image img = plain.render(nullptr);
  const auto rays = s.camera.rayGenerator();
  for (int y = 0; y < 18; ++y)
    for (int x = 0; x < 24; ++x) {
      // Every one of the N terms, each pixel its own: bit for bit the march of all N steps.
      const LightSpaceMarcher::Pixel p = plain.march(rays(x, y), 0, 1);
      EXPECT_EQ(img.at(x, y), p.boundary + p.inScatter) << x << "," << y;
    }
}

TEST(LightSpaceMarch, TheClassesOfABlockPartitionTheTerms) {
  // With M = 2 the four classes' partial sums of one ray add up to its plain N-term sum (only
  // the order of the float additions differs: measured max 1.78e-7 relative).
  const Scene s = sceneFromJson(blobDoc(24, 18));
  const DensityGrid d = buildDensityVolume(s);
  const LightSpaceMarcher m(s, d, lsm(30, 2, LightTransmittance::Traced), s.medium.voxelSize());
  const auto rays = s.camera.rayGenerator();
  double worst = 0.0;
  for (int y = 0; y < 18; y += 3)
    for (int x = 0; x < 24; x += 3) {
      const Vec3 all = m.march(rays(x, y), 0, 1).inScatter;
      Vec3 parts(0.0f);
      for (int k = 0; k < 4; ++k) parts += m.march(rays(x, y), k, 4).inScatter;
      for (int c = 0; c < 3; ++c)
        if (all[c] > 0.0f) worst = std::max(worst, double(std::abs(parts[c] - all[c]) / all[c]));
    }
  std::printf("class partition: worst relative difference %.3g\n", worst);
  EXPECT_LT(worst, 1.78e-7 * 1.5);
}

TEST(LightSpaceMarch, BlockSumAddsOneTermClassFromEveryPixelOfTheWindow) {
  // The interleaved image at p = p's boundary term + Σ over the M×M window of p (clamped at the
  // borders) of each window pixel's own class of terms: exactly what the separable sum adds.
  const int M = 3, w = 20, h = 14;
  const Scene s = sceneFromJson(blobDoc(w, h));
  const DensityGrid d = buildDensityVolume(s);
  const LightSpaceMarcher m(s, d, lsm(27, M, LightTransmittance::Mean), s.medium.voxelSize());
  const Image img = m.render(nullptr);
  const auto rays = s.camera.rayGenerator();
  double worst = 0.0;
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      Vec3 sum = m.march(rays(x, y), 0, 1).boundary;
      std::set<int> classes;
      for (int j = blockWindowStart(y, M, h); j < blockWindowStart(y, M, h) + M; ++j)
        for (int i = blockWindowStart(x, M, w); i < blockWindowStart(x, M, w) + M; ++i) {
          const int k = (i % M) + M * (j % M);
          classes.insert(k);
          sum += m.march(rays(i, j), k, M * M).inScatter;
        }
      EXPECT_EQ(classes.size(), std::size_t(M * M)) << "window of " << x << "," << y;
      for (int c = 0; c < 3; ++c)
        worst = std::max(
            worst, double(std::abs(sum[c] - img.at(x, y)[c]) / std::max(1e-12f, std::abs(sum[c]))));
    }
  std::printf("block sum: worst relative difference %.3g\n", worst);
  // Measured 2.33e-7 (float sums in another order).
  EXPECT_LT(worst, 2.33e-7 * 1.5);
}

TEST(LightSpaceMarch, InterleavedEqualsThePlainMarchWhereRadianceIsConstantAcrossTheBlock) {
  // Homogeneous fog seen head-on through a narrow field of view, lit by a directional light
  // along the view direction: every pixel's ray has nearly the same terms, so summing one class
  // from each of M² pixels gives the plain march (measured 1.11e-5 relative L2 at M = 4).
  Json doc = homogeneousBoxDoc(1.0f, 1.5f, 0.9f, Vec3(0.0f), 1.0f, 32, 24, 8);
  doc["lights"][0] = {{"type", "directional"}, {"direction", {0, 0, 1}}, {"irradiance", 2.0}};
  doc["camera"]["fov_y_deg"] = 2.0;
  const Scene s = sceneFromJson(doc);
  const DensityGrid d = buildDensityVolume(s);
  const float delta1 = s.medium.voxelSize();
  const Image plain =
      LightSpaceMarcher(s, d, lsm(64, 1, LightTransmittance::Mean), delta1).render(nullptr);
  const Image inter =
      LightSpaceMarcher(s, d, lsm(64, 4, LightTransmittance::Mean), delta1).render(nullptr);
  std::printf("constant region, M = 4 vs plain: rel L2 %.3g\n", relL2(inter, plain));
  EXPECT_LT(relL2(inter, plain), 1.11e-5 * 1.5);
}

TEST(LightSpaceMarch, TracedTransmittanceConvergesToExactAsStepsGrow) {
  // Homogeneous fog, spot light, HG phase, no objects. Measured relative L2 against exact
  // (march_step = delta1 = 1/512): 16 steps 1.61e-3, 64 steps 7.31e-5, 256 steps 4.12e-6.
  Scene s = sceneFromJson(spotFogDoc(40, 30));
  const double step = 1.0 / 512;
  const Image exact =
      renderMethod(s, {{"method", "exact"}, {"march_step", step}, {"delta1", step}});
  double prev = 1e9;
  const std::map<int, double> measured = {{16, 1.61e-3}, {64, 7.31e-5}, {256, 4.12e-6}};
  for (const auto& [steps, tol] : measured) {
    const Image img = renderMethod(s, {{"method", "light-space-march"},
                                       {"steps", steps},
                                       {"interleave", 1},
                                       {"light_transmittance", "traced"},
                                       {"delta1", step}});
    const double err = relL2(img, exact);
    std::printf("light-space-march traced, %d steps: rel L2 %.3g\n", steps, err);
    EXPECT_LT(err, tol * 1.5) << steps << " steps";
    EXPECT_LT(err, prev) << steps << " steps";
    prev = err;
  }
}

TEST(LightSpaceMarch, MeanTransmittanceIsExactForAHomogeneousMedium) {
  // D̄ = D where the density is uniform: e^(−σt·D̄·d) is the traced transmittance (measured
  // 1.8e-10 relative L2 between the two).
  const Scene s = sceneFromJson(spotFogDoc(24, 18));
  const DensityGrid d = buildDensityVolume(s);
  const float delta1 = 1.0f / 256;
  const Image mean =
      LightSpaceMarcher(s, d, lsm(32, 2, LightTransmittance::Mean), delta1).render(nullptr);
  const Image traced =
      LightSpaceMarcher(s, d, lsm(32, 2, LightTransmittance::Traced), delta1).render(nullptr);
  std::printf("homogeneous: mean vs traced rel L2 %.3g\n", relL2(mean, traced));
  EXPECT_LT(relL2(mean, traced), 1.8e-10 * 1.5);
  EXPECT_NEAR(meanDensity(d), 1.0f, 1e-6f);
}

TEST(LightSpaceMarch, ShadowMapsAgreeWithRayTracedVisibility) {
  // A sphere between a light and the box: the shadow-map test of points in the box against
  // Embree's shadow ray, for a spot (2D map), a point (cube map) and a directional light
  // (orthographic map), with the maps of shading/shadow_projection.h that the GPU uses too (depth
  // compare, no PCF, bias one texel). Measured disagreement at 512² texels: 0.34 %, 0.21 %,
  // 0.08 % of the points (texels straddling the silhouette).
  Json doc = homogeneousBoxDoc(1.0f, 1.0f, 1.0f, Vec3(0.5f, 1.6f, 0.5f), 1.0f, 8, 8, 8);
  doc["objects"] = Json::array(
      {{{"type", "sphere"}, {"center", {0.5, 1.25, 0.5}}, {"radius", 0.12}, {"albedo", 0.5}}});
  const Scene s = sceneFromJson(doc);
  Light spot;
  spot.type = Light::Type::Spot;
  spot.position = Vec3(0.5f, 1.6f, 0.5f);
  spot.direction = Vec3(0, -1, 0);
  spot.cosInner = std::cos(30 * kPi / 180);
  spot.cosOuter = std::cos(50 * kPi / 180);
  Light point;
  point.position = Vec3(0.5f, 1.6f, 0.5f);
  Light sun;
  sun.type = Light::Type::Directional;
  sun.direction = glm::normalize(Vec3(0.2f, -1.0f, 0.1f));
  const std::vector<std::pair<Light, double>> cases = {
      {spot, 0.0034}, {point, 0.0021}, {sun, 0.0008}};
  ShadowMapSettings settings;  // depth compare, no PCF, one texel of bias
  settings.type = ShadowMapSettings::Type::Depth;
  settings.resolution = 512;
  settings.filter = 1;
  for (const auto& [light, measured] : cases) {
    Scene one = s;
    one.lights = {light};
    const ShadowMap map(one, settings);
    int wrong = 0, shadowed = 0, n = 0;
    for (int k = 0; k < 40; ++k)
      for (int j = 0; j < 40; ++j)
        for (int i = 0; i < 40; ++i, ++n) {
          const Vec3 x((i + 0.5f) / 40, (j + 0.5f) / 40, (k + 0.5f) / 40);
          Light::Incident inc;
          light.incident(x, inc);
          const bool occluded = s.objects->occluded(x, inc.toLight, 0.0f, inc.distance);
          shadowed += occluded;
          wrong += (map.visibility(0, x) > 0.0f) == occluded;
        }
    std::printf("shadow map, light type %d: %.4f of the points disagree (%d shadowed of %d)\n",
                int(light.type), double(wrong) / n, shadowed, n);
    EXPECT_GT(shadowed, n / 50) << "the sphere must shadow part of the box";
    EXPECT_LT(double(wrong) / n, measured * 1.5) << "light type " << int(light.type);
  }
}

TEST(LightSpaceMarch, WithObjectsAgreesWithExact) {
  // A sphere above the fog shadows a spot light's cone; surfaces are shaded as every CPU method
  // shades them (SurfaceRadiance). Traced transmittance, 128 steps: the error left is the
  // shadow map's texels (render.shadow_map defaults: 1024², 3×3 PCF) and the step count
  // (measured rel L2 6.91e-3 against exact).
  Json doc = spotFogDoc(40, 30);
  doc["objects"] = Json::array(
      {{{"type", "sphere"}, {"center", {0.45, 1.2, 0.5}}, {"radius", 0.1}, {"albedo", 0.5}},
       {{"type", "box"}, {"min", {-1, -0.2, -1}}, {"max", {2, -0.1, 2}}, {"albedo", 0.7}}});
  Scene s = sceneFromJson(doc);
  const double step = 1.0 / 256;
  const Image exact =
      renderMethod(s, {{"method", "exact"}, {"march_step", step}, {"delta1", step}});
  const Image img = renderMethod(s, {{"method", "light-space-march"},
                                     {"steps", 128},
                                     {"interleave", 1},
                                     {"light_transmittance", "traced"},
                                     {"delta1", step}});
  const double err = relL2(img, exact);
  std::printf("light-space-march with objects: rel L2 %.3g\n", err);
  EXPECT_LT(err, 6.91e-3 * 1.5);
}

TEST(LightSpaceMarch, KeysAreValidatedByName) {
  const Scene s = sceneFromJson(spotFogDoc(16, 12));
  const auto err = [&](const Json& extra) {
    Json r = {{"method", "light-space-march"}};
    r.update(extra);
    return errorOf(s, r);
  };
  EXPECT_NE(err({{"steps", 0}}).find("render.steps"), std::string::npos);
  EXPECT_NE(err({{"steps", 2.5}}).find("render.steps"), std::string::npos);
  EXPECT_NE(err({{"interleave", 33}}).find("render.interleave"), std::string::npos);
  EXPECT_NE(err({{"interleave", 4}, {"steps", 8}}).find("render.interleave"), std::string::npos);
  EXPECT_NE(err({{"light_transmittance", "exact"}}).find("render.light_transmittance"),
            std::string::npos);
  // The shadow maps' resolution is render.shadow_map's (the GPU's too); the old key is gone.
  EXPECT_NE(err({{"shadow_map", {{"resolution", 8}}}}).find("render.shadow_map.resolution"),
            std::string::npos);
  EXPECT_NE(err({{"shadow_map_resolution", 64}}).find("shadow_map_resolution"), std::string::npos);
  // A block larger than the image, and several rays per pixel, cannot be interleaved.
  Scene tiny = s;
  tiny.camera.width = 3;
  EXPECT_NE(
      errorOf(tiny, {{"method", "light-space-march"}, {"interleave", 4}}).find("render.interleave"),
      std::string::npos);
  Scene aa = s;
  aa.camera.spp = 4;
  EXPECT_NE(errorOf(aa, {{"method", "light-space-march"}}).find("camera.spp"), std::string::npos);
  EXPECT_EQ(err({{"steps", 64}, {"interleave", 2}}), "");
}

// ------------------------------------------------------------------ radial-blur

RadialBlurSettings blur(int samples, float decay, float weight, float exposure) {
  RadialBlurSettings s;
  s.samples = samples;
  s.decay = decay;
  s.weight = weight;
  s.exposure = exposure;
  return s;
}

TEST(RadialBlur, OneSampleWithDecayOneIsThePrePassTimesWeightTimesExposure) {
  const Scene s = sceneFromJson(blurDoc(24, 18));
  const DensityGrid d = buildDensityVolume(s);
  MarchSettings ms;
  ms.step = s.medium.voxelSize();
  const Image pre = radialBlurPrePass(s, d, 0, 1, ms);
  float ax, ay;
  radialBlurLightPosition(s, 0, 0.5f, ax, ay);
  const Image r = radialBlur(pre, 1, 24, 18, ax, ay, blur(1, 1.0f, 2.5f, 0.3f));
  for (int y = 0; y < 18; ++y)
    for (int x = 0; x < 24; ++x) EXPECT_EQ(r.at(x, y), pre.at(x, y) * (0.3f * 2.5f / 1.0f));
  // The whole method: the base image T·background plus that.
  Scene bg = s;
  bg.background = Vec3(0.1f, 0.2f, 0.3f);
  const Image img = renderRadialBlur(bg, d, blur(1, 1.0f, 2.5f, 0.3f), ms, ms.step);
  const auto none = [](const Vec3&, const Vec3&) { return Vec3(0.0f); };
  const Image base = marchImage(bg, d, none, ms, nullptr, ms.step);
  for (int y = 0; y < 18; ++y)
    for (int x = 0; x < 24; ++x)
      EXPECT_EQ(img.at(x, y), base.at(x, y) + pre.at(x, y) * (0.3f * 2.5f / 1.0f));
}

TEST(RadialBlur, SumsDecayingSamplesAlongTheRayToTheLight) {
  // Eq. 4 by hand at one pixel of a pre-pass that is 1 at one texel and 0 elsewhere: the sample
  // i that lands on it contributes exposure·weight·decay^i/n.
  Image pre(16, 16);
  pre.at(4, 8) = Vec3(1.0f);
  // Light at (0.5, 8.5), pixel (12, 8): Δφ = (12.5 − 0.5)·0.75/9 = 1 pixel; sample i = 8 is at
  // x = 4.5, the texel's centre.
  const Image r = radialBlur(pre, 1, 16, 16, 0.5f, 8.5f, [] {
    RadialBlurSettings s = blur(9, 0.9f, 2.0f, 0.5f);
    s.density = 0.75f;
    return s;
  }());
  EXPECT_FLOAT_EQ(r.at(12, 8).x, 0.5f * 2.0f * std::pow(0.9f, 8.0f) / 9.0f);
  EXPECT_EQ(r.at(12, 3), Vec3(0.0f));  // its ray to the light never meets the texel
}

// A point or spot light inside the medium's box is refused (UnsupportedSceneError): the blur
// would spread its glow over the whole frame (the glow scene: 7 586 % relative L1 against
// exact); one just outside the box renders.
TEST(RadialBlur, ALightInsideTheMediumIsRefused) {
  Json doc = blobDoc(16, 12);
  doc["lights"][0]["position"] = {0.5, 0.5, 0.5};
  try {
    Scene s = sceneFromJson(doc);
    s.render = {{"method", "radial-blur"}};
    createMethod(s, "", "cpu")->render(s, nullptr);
    ADD_FAILURE() << "rendered a light inside the medium";
  } catch (const UnsupportedSceneError& e) {
    EXPECT_NE(std::string(e.what()).find("lights[0] is inside the medium's box"), std::string::npos)
        << e.what();
  }
  doc["lights"][0]["position"] = {0.5, 1.05, 0.5};
  EXPECT_EQ(errorOf(sceneFromJson(doc), {{"method", "radial-blur"}}), "");
}

TEST(RadialBlur, ALightBehindTheCameraIsAClearError) {
  Json doc = blobDoc(16, 12);
  doc["lights"][0]["position"] = {0.5, 0.5, -3.0};  // behind the camera at z = −2
  const Scene s = sceneFromJson(doc);
  const std::string e = errorOf(s, {{"method", "radial-blur"}});
  EXPECT_NE(e.find("lights[0] is behind the camera"), std::string::npos) << e;
  // A directional light shining towards the camera comes from behind it, too.
  Json sun = blobDoc(16, 12);
  sun["lights"][0] = {{"type", "directional"}, {"direction", {0, 0, 1}}, {"irradiance", 1.0}};
  EXPECT_NE(errorOf(sceneFromJson(sun), {{"method", "radial-blur"}}).find("behind the camera"),
            std::string::npos);
}

TEST(RadialBlur, AnOffScreenLightIsClampedToTheGuardBand) {
  Json doc = blobDoc(40, 30);
  // Far to the right (the camera looks along +z, so its right is −x), in front of the camera.
  doc["lights"][0]["position"] = {-30.0, 0.5, 0.5};
  const Scene s = sceneFromJson(doc);
  float ax, ay;
  radialBlurLightPosition(s, 0, 0.5f, ax, ay);
  EXPECT_FLOAT_EQ(ax, 60.0f);  // (1 + 0.5)·40
  radialBlurLightPosition(s, 0, 0.0f, ax, ay);
  EXPECT_FLOAT_EQ(ax, 40.0f);
  EXPECT_NO_THROW(renderMethod(s, {{"method", "radial-blur"}, {"samples", 4}}));
}

TEST(RadialBlur, DownsampledPrePassHasFewerPixelsAndStaysClose) {
  // Half-resolution pre-pass read bilinearly: measured 2.95e-2 relative L2 from the full one
  // (a light outside the medium; near a light inside it the glow is too sharp for half a pixel).
  Json doc = blobDoc(32, 24);
  doc["lights"][0]["position"] = {0.6, 0.7, -0.4};  // outside the medium, in front of it
  const Scene s = sceneFromJson(doc);
  const DensityGrid d = buildDensityVolume(s);
  MarchSettings ms;
  ms.step = s.medium.voxelSize();
  EXPECT_EQ(radialBlurPrePass(s, d, 0, 2, ms).width(), 16);
  EXPECT_EQ(radialBlurPrePass(s, d, 0, 4, ms).height(), 6);
  RadialBlurSettings full = blur(16, 0.97f, 1.0f, 1.0f), half = full;
  half.downsample = 2;
  const double err =
      relL2(renderRadialBlur(s, d, half, ms, ms.step), renderRadialBlur(s, d, full, ms, ms.step));
  std::printf("radial-blur downsample 2 vs 1: rel L2 %.3g\n", err);
  EXPECT_LT(err, 2.95e-2 * 1.5);
}

TEST(RadialBlur, OccludersArePrePassBlack) {
  // A sphere between the camera and the light is black in the pre-pass; a wall behind the light
  // only ends the march.
  Json doc = blobDoc(32, 24);
  doc["objects"] = Json::array(
      {{{"type", "sphere"}, {"center", {0.55, 0.6, -0.5}}, {"radius", 0.1}, {"albedo", 0.5}},
       {{"type", "box"}, {"min", {-2, -2, 1.5}}, {"max", {3, 3, 1.6}}, {"albedo", 0.5}}});
  const Scene s = sceneFromJson(doc);
  const DensityGrid d = buildDensityVolume(s);
  MarchSettings ms;
  ms.step = s.medium.voxelSize();
  const Image pre = radialBlurPrePass(s, d, 0, 1, ms);
  float ax, ay;
  radialBlurLightPosition(s, 0, 0.5f, ax, ay);
  EXPECT_EQ(pre.at(int(ax), int(ay)), Vec3(0.0f));  // the sphere hides the light
  EXPECT_GT(pre.at(int(ax) + 8, int(ay)).x, 0.0f);  // fog in front of the far wall
}

TEST(RadialBlur, KeysAreValidatedByName) {
  const Scene s = sceneFromJson(blurDoc(16, 12));
  const auto err = [&](const Json& extra) {
    Json r = {{"method", "radial-blur"}};
    r.update(extra);
    return errorOf(s, r);
  };
  for (const auto& [key, bad] : std::vector<std::pair<std::string, Json>>{{"samples", 0},
                                                                          {"samples", 5000},
                                                                          {"density", 0.0},
                                                                          {"density", 1.5},
                                                                          {"weight", -1.0},
                                                                          {"decay", 1.5},
                                                                          {"exposure", -0.1},
                                                                          {"downsample", 3},
                                                                          {"downsample", 8},
                                                                          {"guard_band", 11.0}})
    EXPECT_NE(err({{key, bad}}).find("render." + key), std::string::npos) << key << " " << bad;
  EXPECT_EQ(err({{"samples", 8}, {"decay", 0.9}, {"downsample", 2}}), "");
}

}  // namespace
