/// The per-pixel competitors of the paper's method (docs/competitors.md): `jittered-march`
/// converges to `exact` as its steps grow, its jitter changes nothing where the integrand is
/// constant, downsample 1 is the plain per-pixel march; `froxel` converges to `exact` as its
/// grid refines, its slices cover near…far; both render scene objects on the CPU; bad keys are
/// rejected naming the key.

#include <gtest/gtest.h>

#include "core/metrics.h"
#include "cpu/froxel.h"
#include "shading/screen_march.h"
#include "shading/transport.h"
#include "support/scenes.h"

using namespace scatterlab;
using scatterlab::testing::homogeneousBoxDoc;
using scatterlab::testing::relL2;
using scatterlab::testing::sceneFromJson;

namespace {

/// Gaussian blobs in [0,1]³ (32³), HG phase, a directional light and a point light outside the
/// box (no light inside the medium: no singular pixels), 48×36.
Json blobsDoc() {
  return Json{
      {"medium",
       {{"bounds", {{"min", {0, 0, 0}}, {"max", {1, 1, 1}}}},
        {"density",
         {{"type", "gaussians"},
          {"blobs",
           Json::array({{{"center", {0.5, 0.5, 0.5}}, {"radius", 0.2}, {"weight", 1.0}},
                        {{"center", {0.3, 0.65, 0.4}}, {"radius", 0.12}, {"weight", 1.5}},
                        {{"center", {0.7, 0.35, 0.6}}, {"radius", 0.15}, {"weight", 1.2}}})}}},
        {"resolution", 32},
        {"sigma_t", 4.0},
        {"albedo", 0.7},
        {"phase", {{"type", "henyey-greenstein"}, {"g", 0.3}}}}},
      {"lights",
       Json::array(
           {{{"type", "directional"},
             {"direction", {0.3, -1, 0.2}},
             {"irradiance", {1.0, 0.9, 0.7}}},
            {{"type", "point"}, {"position", {0.5, 1.4, 0.2}}, {"intensity", {1.5, 1.5, 2.0}}}})},
      {"camera",
       {{"position", {0.5, 0.5, -2}},
        {"look_at", {0.5, 0.5, 0.5}},
        {"fov_y_deg", 35},
        {"width", 48},
        {"height", 36}}},
      {"render", {{"delta1", 1.0 / 64}}}};
}

Image render(Scene s, const Json& render) {
  for (auto it = render.begin(); it != render.end(); ++it) s.render[it.key()] = it.value();
  return createMethod(s)->render(s, nullptr).image;
}

/// exact with march_step = 1/4 voxel: the reference of these tests.
Image reference(const Scene& s) {
  return render(s, {{"method", "exact"}, {"backend", "cpu"}, {"march_step", 1.0 / 128}});
}

TEST(JitteredMarch, ConvergesToExactAsStepsGrow) {
  const Scene s = sceneFromJson(blobsDoc());
  const Image ref = reference(s);
  std::vector<double> err;
  for (int steps : {4, 16, 64})
    err.push_back(relL2(render(s, {{"method", "jittered-march"},
                                   {"backend", "cpu"},
                                   {"steps", steps},
                                   {"jitter", "none"}}),
                        ref));
  // Measured (48x36, CPU): 0.0515, 0.000389, 0.000183 (the last near the reference's own step
  // error); the finest limit is 1.5x its measurement.
  EXPECT_LT(err[1], err[0]);
  EXPECT_LT(err[2], err[1]);
  EXPECT_LT(err[2], 0.00028);
}

TEST(Froxel, ConvergesToExactAsTheGridRefines) {
  const Scene s = sceneFromJson(blobsDoc());
  const Image ref = reference(s);
  std::vector<double> err;
  for (int f : {1, 2, 4})
    err.push_back(relL2(render(s, {{"method", "froxel"},
                                   {"backend", "cpu"},
                                   {"froxel_grid", {12 * f, 9 * f, 16 * f}}}),
                        ref));
  // Measured (48x36 image, CPU, slices clipped to the box): 0.174, 0.0578, 0.000234 (at 48x36
  // columns every pixel has its own column); the finest limit is 1.5x its measurement.
  EXPECT_LT(err[1], err[0]);
  EXPECT_LT(err[2], err[1]);
  EXPECT_LT(err[2], 0.00035);
}

TEST(JitteredMarch, JitterChangesNothingWhereTheIntegrandIsConstant) {
  // Uniform density, isotropic phase, sunlight straight down: along the middle image row (an odd
  // height puts a pixel centre on the view axis, so those rays are horizontal) the optical depth
  // to the sun and hence S are the same at every point, and every step adds the same share
  // whatever its offset. Elsewhere the rays tilt, S varies, and the jitter shows.
  Json doc = homogeneousBoxDoc(1.0f, 2.0f, 0.8f, Vec3(0.5f), 1.0f, 41, 31, 16);
  doc["lights"] = Json::array(
      {{{"type", "directional"}, {"direction", {0, -1, 0}}, {"irradiance", {1, 1, 1}}}});
  const Scene s = sceneFromJson(doc);
  const Image none = render(s, {{"method", "jittered-march"}, {"steps", 8}, {"jitter", "none"}});
  const Image ign = render(s, {{"method", "jittered-march"}, {"steps", 8}, {"jitter", "ign"}});
  double rowDiff = 0, elsewhere = 0;
  for (int y = 0; y < 31; ++y)
    for (int x = 0; x < 41; ++x) {
      const double d = std::abs(double(none.at(x, y).x) - ign.at(x, y).x) / none.at(x, y).x;
      (y == 15 ? rowDiff : elsewhere) = std::max(y == 15 ? rowDiff : elsewhere, d);
    }
  // Measured (41x31, 8 steps): 0 on the middle row (bit for bit), 0.0192 elsewhere.
  EXPECT_LT(rowDiff, 1e-6);
  EXPECT_GT(elsewhere, 0.0128);
}

TEST(JitteredMarch, DownsampleOneIsThePlainPerPixelMarch) {
  // The method at downsample 1 against the per-pixel march written out here: N equal steps of
  // the ray's piece inside the box, S traced at the step midpoints.
  const Scene s = sceneFromJson(blobsDoc());
  const int steps = 12;
  const Image img = render(
      s, {{"method", "jittered-march"}, {"steps", steps}, {"jitter", "none"}, {"downsample", 1}});
  const DensityGrid density = buildDensityVolume(s);
  const SourceRadiance source(s, density, 1.0f / 64);
  const auto rays = s.camera.rayGenerator();
  double worst = 0;
  for (int y = 0; y < s.camera.height; ++y)
    for (int x = 0; x < s.camera.width; ++x) {
      const Ray r = rays(x, y);
      Vec3 L(0.0f);
      float T = 1.0f, t0, t1;
      if (s.medium.bounds.intersect(r, t0, t1) && t1 > t0) {
        const float dt = (t1 - t0) / float(steps);
        for (int k = 0; k < steps; ++k) {
          const Vec3 p = r.at(t0 + (float(k) + 0.5f) * dt);
          const float a = std::exp(-s.medium.sigmaT * density.sample(p) * dt);
          L += T * s.medium.albedo * (1.0f - a) * source(p, -r.dir);
          T *= a;
        }
      }
      const Vec3 want = L + T * s.background;
      for (int c = 0; c < 3; ++c)
        worst = std::max(
            worst, std::abs(double(img.at(x, y)[c]) - want[c]) / std::max(1e-3, double(want[c])));
    }
  // Measured: 1.22e-5 (float rounding of the two loops' sample points).
  EXPECT_LT(worst, 1.8e-5);
}

TEST(JitteredMarch, DownsampledImagesApproachTheFullResolutionOne) {
  const Scene s = sceneFromJson(blobsDoc());
  const Image full = render(s, {{"method", "jittered-march"}, {"jitter", "none"}});
  const double e2 =
      relL2(render(s, {{"method", "jittered-march"}, {"jitter", "none"}, {"downsample", 2}}), full);
  const double e4 =
      relL2(render(s, {{"method", "jittered-march"}, {"jitter", "none"}, {"downsample", 4}}), full);
  // Measured relative L2 against downsample 1 (48x36): 0.0621 at 2, 0.203 at 4.
  EXPECT_LT(e2, e4);
  EXPECT_LT(e2, 0.093);
  EXPECT_LT(e4, 0.30);
}

TEST(Froxel, ExponentialSlicesCoverNearToFar) {
  const Scene s = sceneFromJson(blobsDoc());
  FroxelSettings fs;
  fs.grid = IVec3(8, 6, 16);
  const FroxelSlicing f = froxelSlicing(s, fs);
  // The camera at z = −2 looks along +z at the unit box: view depths 2 … 3 (corners at
  // x, y = 0 or 1 lie at depth 2 or 3 along the axis).
  EXPECT_FLOAT_EQ(f.near, 2.0f);
  EXPECT_FLOAT_EQ(f.far, 3.0f);
  EXPECT_TRUE(f.exponential);
  EXPECT_FLOAT_EQ(f.depth(0), f.near);
  EXPECT_NEAR(f.depth(16), f.far, 1e-6 * f.far);
  const float ratio = f.depth(1) / f.depth(0);
  for (int k = 1; k <= 16; ++k) {
    EXPECT_NEAR(f.depth(float(k)) / f.depth(float(k - 1)), ratio, 1e-5) << k;
    EXPECT_NEAR(f.coordinate(f.depth(float(k))), float(k), 1e-4) << k;
  }
  fs.distribution = DepthDistribution::Linear;
  fs.near = 0.5f;
  fs.far = 4.0f;
  const FroxelSlicing lin = froxelSlicing(s, fs);
  EXPECT_FLOAT_EQ(lin.depth(0), 0.5f);
  EXPECT_FLOAT_EQ(lin.depth(8), 2.25f);
  EXPECT_FLOAT_EQ(lin.depth(16), 4.0f);
  EXPECT_FLOAT_EQ(lin.coordinate(0.1f), 0.0f);
  EXPECT_FLOAT_EQ(lin.coordinate(9.0f), 16.0f);
}

TEST(Froxel, TransmittanceMapApproachesTracedAsItRefines) {
  const Scene s = sceneFromJson(blobsDoc());
  const Json grid = {48, 36, 64};
  const Image traced = render(s, {{"method", "froxel"}, {"froxel_grid", grid}});
  std::vector<double> err;
  for (int res : {8, 32})
    err.push_back(relL2(render(s, {{"method", "froxel"},
                                   {"froxel_grid", grid},
                                   {"light_transmittance", "map"},
                                   {"transmittance_map_resolution", res}}),
                        traced));
  // Measured relative L2 against traced: 0.0428 at 8³, 0.00311 at 32³.
  EXPECT_LT(err[1], err[0]);
  EXPECT_LT(err[1], 0.0047);
}

/// The unit box of fog under a point light, a sphere shadowing it from above, a lit floor box
/// seen through the fog.
Json objectsDoc() {
  Json doc = homogeneousBoxDoc(1.0f, 1.5f, 0.8f, Vec3(0.5f, 1.6f, 0.5f), 3.0f, 40, 30, 32);
  doc["objects"] = Json::array(
      {{{"type", "sphere"}, {"center", {0.5, 1.3, 0.5}}, {"radius", 0.1}, {"albedo", 0.5}},
       {{"type", "box"}, {"min", {-1, -0.3, -1}}, {"max", {2, 0.15, 2}}, {"albedo", 0.6}}});
  doc["camera"]["position"] = {0.5, 1.2, -1.5};
  return doc;
}

TEST(Competitors, RenderObjectsOnTheCpuLikeExact) {
  const Scene s = sceneFromJson(objectsDoc());
  const Image ref = reference(s);
  Scene noObjects = s;
  noObjects.objects.reset();
  const double objectsShare = relL2(reference(noObjects), ref);
  const double jm = relL2(render(s, {{"method", "jittered-march"}, {"steps", 64}}), ref);
  const double fx = relL2(render(s, {{"method", "froxel"}, {"froxel_grid", {40, 30, 64}}}), ref);
  // Measured relative L2 to exact (40x30): jittered-march (64 steps) 0.00907, froxel
  // (40x30x64) 0.0115 (0.0156 before its slices were clipped to the medium box), far below what
  // the objects change (0.586: shadow and floor).
  EXPECT_LT(jm, 0.0136);
  EXPECT_LT(fx, 0.0173);
  EXPECT_GT(objectsShare, 0.39);
}

/// createMethod's error for `render` on the blob scene.
std::string errorOf(const Json& render) {
  Scene s = sceneFromJson(blobsDoc());
  for (auto it = render.begin(); it != render.end(); ++it) s.render[it.key()] = it.value();
  try {
    const auto m = createMethod(s);
    m->render(s, nullptr);
  } catch (const Error& e) {
    return e.what();
  }
  return "";
}

TEST(Competitors, BadKeysAreRejectedNamingTheKey) {
  const Json jm = "jittered-march", fx = "froxel";
  const std::vector<std::pair<Json, std::string>> cases = {
      {{{"method", jm}, {"steps", 0}}, "render.steps"},
      {{{"method", jm}, {"steps", 2.5}}, "render.steps"},
      {{{"method", jm}, {"jitter", "blue"}}, "render.jitter"},
      {{{"method", jm}, {"downsample", 3}}, "render.downsample"},
      {{{"method", jm}, {"downsample", 8}}, "render.downsample"},
      {{{"method", fx}, {"froxel_grid", {16, 9}}}, "render.froxel_grid"},
      {{{"method", fx}, {"froxel_grid", {16, 0, 8}}}, "render.froxel_grid"},
      {{{"method", fx}, {"froxel_grid", {1024, 1024, 1024}}}, "render.froxel_grid"},
      {{{"method", fx}, {"depth_distribution", "log"}}, "render.depth_distribution"},
      {{{"method", fx}, {"near", -1}}, "render.near"},
      {{{"method", fx}, {"near", 3}, {"far", 2}}, "render.far"},
      {{{"method", fx}, {"near", 5}}, "render.near"},
      {{{"method", fx}, {"light_transmittance", "shadow"}}, "render.light_transmittance"},
      {{{"method", fx}, {"transmittance_map_resolution", 1}},
       "render.transmittance_map_resolution"},
  };
  Scene spp = sceneFromJson(blobsDoc());
  spp.camera.spp = 4;
  spp.render["method"] = "froxel";
  try {
    createMethod(spp);
    ADD_FAILURE() << "froxel accepted camera.spp = 4";
  } catch (const ConfigError& e) {
    EXPECT_NE(std::string(e.what()).find("camera.spp"), std::string::npos) << e.what();
  }
  for (const auto& [render, key] : cases) {
    const std::string e = errorOf(render);
    EXPECT_NE(e.find(key), std::string::npos) << render.dump() << " -> '" << e << "'";
  }
}

}  // namespace
