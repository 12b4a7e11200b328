// scatterlab::Renderer (api/renderer.h): re-rendering over a kept density must equal a fresh
// render; light paths; what moves with time; errors leave the renderer as it was.
#include <gtest/gtest.h>

#include "api/scatterlab.h"
#ifdef SCATTERLAB_HAS_GPU
#include "gpu/context.h"
#include "gpu/gl.h"
#endif
#include "support/scenes.h"

namespace scatterlab {
namespace {

using testing::homogeneousBoxDoc;

/// Gaussian blobs (one moving with `velocity`) in the unit box, a point light, 32x24 px.
Json blobDoc(Vec3 velocity = Vec3(0.0f)) {
  Json doc = homogeneousBoxDoc(1.0f, 3.0f, 0.7f, Vec3(0.5f, 1.3f, 0.5f), 3.0f, 32, 24, 24);
  doc["medium"]["density"] = {
      {"type", "gaussians"},
      {"blobs", Json::array({{{"center", {0.5, 0.5, 0.5}}, {"radius", 0.2}, {"weight", 1.0}},
                             {{"center", {0.3, 0.6, 0.4}},
                              {"radius", 0.12},
                              {"weight", 0.8},
                              {"velocity", {velocity.x, velocity.y, velocity.z}}}})}};
  return doc;
}

/// blobDoc() for `method`: gradient and adaptive with their samples (the scene is small enough
/// that their whole-scene fallback would render it as per-voxel does); gradient from 1000
/// jittered samples, not its default ceiling of 8000 (7 389 on this 24³ volume: 1.3 s per render
/// on llvmpipe, and what these tests check does not depend on the count).
Json methodDoc(const std::string& method) {
  Json doc = blobDoc();
  if (method == "adaptive" || method == "gradient") doc["render"]["voxel_switch"] = 0;
  if (method == "gradient") doc["render"]["sampler"] = {{"type", "jittered"}, {"count", 1000}};
  return doc;
}

Image freshRender(Json doc, const std::string& method, const std::string& backend) {
  initialize();
  const Scene s = parseScene(doc, ".");
  return createMethod(s, method, backend)->render(s, nullptr).image;
}

double maxAbsDiff(const Image& a, const Image& b) {
  return compareImages(a, b).maxAbs;
}

TEST(LightPath, InterpolatesLinearlyAndHoldsAtTheEnds) {
  const Json light = Json::parse(R"({"path": [{"t": 1, "position": [0,0,0]},
                                              {"t": 3, "position": [2,4,0]},
                                              {"t": 4, "position": [2,4,8]}]})");
  const std::vector<PathKey> path = readLightPath(light, "lights[0]");
  ASSERT_EQ(path.size(), 3u);
  EXPECT_EQ(pathPosition(path, 0.0), Vec3(0, 0, 0));
  EXPECT_EQ(pathPosition(path, 2.0), Vec3(1, 2, 0));
  EXPECT_EQ(pathPosition(path, 3.5), Vec3(2, 4, 4));
  EXPECT_EQ(pathPosition(path, 9.0), Vec3(2, 4, 8));
}

TEST(LightPath, BadPathsNameTheKey) {
  const auto message = [](const char* text) -> std::string {
    try {
      readLightPath(Json::parse(text), "lights[2]");
    } catch (const ConfigError& e) {
      return e.what();
    }
    return "";
  };
  EXPECT_NE(message(R"({"path": [{"t": 0, "position": [0,0,0]}, {"t": 0, "position": [1,0,0]}]})")
                .find("'lights[2].path[1].t'"),
            std::string::npos);
  EXPECT_NE(message(R"({"path": [{"t": 0, "position": [0,0,0]}, {"t": -1, "position": [1,0,0]}]})")
                .find("strictly increase"),
            std::string::npos);
  EXPECT_NE(message(R"({"path": []})").find("'lights[2].path': expected a non-empty array"),
            std::string::npos);
  EXPECT_NE(message(R"({"path": [{"t": 0}]})").find("lights[2].path[0].position"),
            std::string::npos);
  EXPECT_NE(message(R"({"path": [{"t": 0, "position": [0,0,0], "speed": 1}]})").find("speed"),
            std::string::npos);
}

TEST(Renderer, WhatMovesWithTime) {
  EXPECT_FALSE(densityMovesWithTime(blobDoc()["medium"]["density"]));
  EXPECT_TRUE(densityMovesWithTime(blobDoc(Vec3(0.1f, 0, 0))["medium"]["density"]));
  EXPECT_FALSE(densityMovesWithTime(Json::parse(R"({"type": "uniform", "value": 1})")));
  EXPECT_TRUE(densityMovesWithTime(Json::parse(R"({"type": "uniform", "value": 1, "rate": 2})")));
  EXPECT_FALSE(densityMovesWithTime(Json::parse(R"({"type": "vdb", "file": "x.vdb"})")));
  EXPECT_TRUE(densityMovesWithTime(Json::parse(R"({"type": "sog", "frames": ["a.sog"]})")));
  EXPECT_TRUE(densityMovesWithTime(Json::parse(R"({"type": "dusty-room"})")));
}

/// Moving the light over a kept density gives the image a fresh render gives, for every
/// volume pipeline on the CPU.
TEST(Renderer, KeptDensityEqualsFreshRenderCpu) {
  initialize();
  for (const char* method : {"per-voxel", "gradient", "adaptive"}) {
    SCOPED_TRACE(method);
    Renderer r(methodDoc(method), ".", method, "cpu");
    const RenderResult first = r.render();
    EXPECT_FALSE(first.stats.extra.at("density_reused").get<bool>());
    r.set("lights.0.position=[0.2,1.1,0.3]");
    r.set("camera.fov_y_deg=35");
    const RenderResult second = r.render();
    EXPECT_TRUE(second.stats.extra.at("density_reused").get<bool>());
    // The density stage is skipped altogether, and so is the sampler (it reads the medium
    // only); S at the kept samples is evaluated for the moved light.
    for (const auto& [stage, ms] : second.stats.timingsMs) {
      EXPECT_NE(stage, "density");
      EXPECT_NE(stage, "sampling");
    }
    if (std::string(method) != "per-voxel") {
      EXPECT_FALSE(first.stats.extra.at("samples_reused").get<bool>());
      EXPECT_TRUE(second.stats.extra.at("samples_reused").get<bool>());
    }
    Json moved = methodDoc(method);
    applyOverride(moved, "lights.0.position=[0.2,1.1,0.3]");
    applyOverride(moved, "camera.fov_y_deg=35");
    EXPECT_EQ(maxAbsDiff(second.image, freshRender(moved, method, "cpu")), 0.0);
  }
}

TEST(Renderer, KeptDensityEqualsFreshRenderGpu) {
#ifdef SCATTERLAB_HAS_GPU
  std::string why;
  if (!gpu::tryContext(&why)) GTEST_SKIP() << why;
#else
  GTEST_SKIP() << "built without the GPU backend";
#endif
  initialize();
  Renderer r(methodDoc("gradient"), ".", "gradient", "gpu");
  r.render();
  r.set("lights.0.position=[0.2,1.1,0.3]");
  const RenderResult second = r.render();
  EXPECT_TRUE(second.stats.extra.at("density_reused").get<bool>());
  Json moved = methodDoc("gradient");
  applyOverride(moved, "lights.0.position=[0.2,1.1,0.3]");
  const Image fresh = freshRender(moved, "gradient", "gpu");
  EXPECT_EQ(maxAbsDiff(second.image, fresh), 0.0);
  // Pass timings are those of this render alone (not summed with the first one's).
  EXPECT_FALSE(second.stats.extra.at("gpu_ms").contains("density"));
}

/// Interactive re-rendering: after a camera move with an isotropic phase function only the march
/// runs, and the image equals a fresh render of the moved camera; a light move, an anisotropic
/// phase function or dynamic sampling (camera-weighted error) rebuild the radiance volume.
void radianceReuse(const char* backend) {
  initialize();
  for (const char* method : {"per-voxel", "gradient", "adaptive"}) {
    SCOPED_TRACE(std::string(method) + " " + backend);
    Renderer r(methodDoc(method), ".", method, backend);
    EXPECT_FALSE(r.render().stats.extra.at("radiance_reused").get<bool>());
    r.set("camera.position=[0.6,0.55,-1.4]");
    const RenderResult moved = r.render();
    const bool refines = std::string(method) == "adaptive";
    EXPECT_EQ(moved.stats.extra.at("radiance_reused").get<bool>(), !refines);
    if (!refines) {
      for (const auto& [stage, ms] : moved.stats.timingsMs)
        EXPECT_TRUE(stage == "march" || stage == "total") << stage;
    }
    Json doc = methodDoc(method);
    applyOverride(doc, "camera.position=[0.6,0.55,-1.4]");
    EXPECT_EQ(maxAbsDiff(moved.image, freshRender(doc, method, backend)), 0.0);
    r.set("background=[0.1,0.1,0.2]");  // the march's only
    r.set("camera.width=40");           // dynamic sampling reads only the camera's position
    EXPECT_TRUE(r.render().stats.extra.at("radiance_reused").get<bool>());
    r.set("lights.0.position=[0.2,1.1,0.3]");
    EXPECT_FALSE(r.render().stats.extra.at("radiance_reused").get<bool>());
    r.set("medium.phase={\"type\":\"henyey-greenstein\",\"g\":0.4}");
    r.render();
    r.set("camera.position=[0.5,0.5,-1.5]");
    EXPECT_FALSE(r.render().stats.extra.at("radiance_reused").get<bool>());
  }
}

TEST(Renderer, CameraMoveWithIsotropicPhaseMarchesOnlyCpu) {
  radianceReuse("cpu");
}

TEST(Renderer, CameraMoveWithIsotropicPhaseMarchesOnlyGpu) {
#ifdef SCATTERLAB_HAS_GPU
  std::string why;
  if (!gpu::tryContext(&why)) GTEST_SKIP() << why;
  radianceReuse("gpu");
#else
  GTEST_SKIP() << "built without the GPU backend";
#endif
}

// An engine's frame: the image left in a GL texture (no read-back), equal to the read-back image
// of the same frame once read; a camera move on the kept frame marches into a new texture.
TEST(Renderer, ImageStaysOnTheGpuWhenAsked) {
#ifdef SCATTERLAB_HAS_GPU
  std::string why;
  if (!gpu::tryContext(&why)) GTEST_SKIP() << why;
  initialize();
  Renderer r(methodDoc("gradient"), ".", "gradient", "gpu");
  const Image host = r.render().image;
  r.keepImageOnDevice(true);
  const RenderResult dev = r.render();
  ASSERT_TRUE(dev.deviceImage.has_value());
  EXPECT_EQ(dev.image.width(), 0);
  EXPECT_EQ(dev.deviceImage->width, 32);
  EXPECT_EQ(dev.deviceImage->height, 24);
  EXPECT_FALSE(dev.stats.extra["gpu_ms"].contains("read-back")) << dev.stats.extra["gpu_ms"];
  std::vector<float> rgba(32 * 24 * 4);
  // A render leaves scatterlab's context current on no thread (free for the next thread to
  // render, issue 37): a caller reading its texture without a shared context makes it current.
  EXPECT_FALSE(gpu::glContextCurrent());
  gpu::context();
  glGetTextureImage(dev.deviceImage->texture, 0, GL_RGBA, GL_FLOAT,
                    GLsizei(rgba.size() * sizeof(float)), rgba.data());
  double worst = 0.0;
  for (std::size_t i = 0; i < 32 * 24; ++i) {
    for (int c = 0; c < 3; ++c)
      worst = std::max(worst, double(std::abs(rgba[4 * i + c] - host.pixels()[i][c])));
    worst = std::max(worst, double(std::abs(rgba[4 * i + 3] - host.alpha()[i])));
  }
  EXPECT_EQ(worst, 0.0);
  r.keepImageOnDevice(false);
  const RenderResult back = r.render();
  EXPECT_FALSE(back.deviceImage.has_value());
  EXPECT_EQ(maxAbsDiff(back.image, host), 0.0);
  // The CPU backend has no device: the image comes back as usual.
  Renderer c(blobDoc(), ".", "gradient", "cpu");
  c.keepImageOnDevice(true);
  const RenderResult cr = c.render();
  EXPECT_FALSE(cr.deviceImage.has_value());
  EXPECT_EQ(cr.image.width(), 32);
#else
  GTEST_SKIP() << "built without the GPU backend";
#endif
}

TEST(Renderer, MovingMediumIsRebuiltAtTheNewTime) {
  initialize();
  const Json doc = blobDoc(Vec3(0.2f, 0, 0));
  Renderer r(doc, ".", "per-voxel", "cpu");
  r.render();
  r.setTime(0.5);
  const RenderResult later = r.render();
  EXPECT_FALSE(later.stats.extra.at("density_reused").get<bool>());
  Json at = doc;
  at["medium"]["density"]["time"] = 0.5;
  EXPECT_EQ(maxAbsDiff(later.image, freshRender(at, "per-voxel", "cpu")), 0.0);
  // A still medium keeps its density across times.
  Renderer still(blobDoc(), ".", "per-voxel", "cpu");
  still.render();
  still.setTime(0.5);
  EXPECT_TRUE(still.render().stats.extra.at("density_reused").get<bool>());
}

TEST(Renderer, BadSetLeavesTheSceneAsItWas) {
  initialize();
  Renderer r(blobDoc(), ".", "per-voxel", "cpu");
  EXPECT_THROW(r.set("lights.4.position=[0,0,0]"), ConfigError);
  EXPECT_THROW(r.set("camera.width=0"), ConfigError);
  EXPECT_THROW(r.set("render.nonsense=1"), ConfigError);
  EXPECT_EQ(r.scene().camera.width, 32);
  EXPECT_EQ(r.document(), blobDoc());
  EXPECT_NO_THROW(r.render());
}

TEST(Renderer, SetOutsideTheMediumKeepsTheMediumAndItsDocument) {
  // set() of a key outside the medium detaches the medium instead of copying and comparing it
  // (issue 33: fig3's 800 blobs made each set() ~1 ms); the document and the kept density are as
  // a full rebuild leaves them.
  initialize();
  Renderer r(blobDoc(), ".", "per-voxel", "cpu");
  r.render();
  r.set("lights.0.position=[0.4,0.6,0.5]");
  Json want = blobDoc();
  want["lights"][0]["position"] = {0.4, 0.6, 0.5};
  EXPECT_EQ(r.document(), want);
  EXPECT_EQ(r.scene().lights[0].position, Vec3(0.4f, 0.6f, 0.5f));
  EXPECT_TRUE(r.render().stats.extra.at("density_reused").get<bool>());
  r.set("medium.sigma_t=3");  // a medium key: the medium is parsed again
  want["medium"]["sigma_t"] = 3;
  EXPECT_EQ(r.document(), want);
  EXPECT_EQ(r.scene().medium.sigmaT, 3.0f);
}

// setAll: the assignments in order, the scene parsed once — the document and scene of one set()
// a key; all or nothing where any of them fails, in the override (an index past the lights) or
// in the parse after them (an unknown render key), also when two change the same light.
TEST(Renderer, SetAllIsTheSetsInOrderAndAllOrNothing) {
  initialize();
  Renderer one(blobDoc(), ".", "per-voxel", "cpu"), all(blobDoc(), ".", "per-voxel", "cpu");
  one.render();
  all.render();
  const std::vector<std::string> changes = {"lights.0.position=[0.4,0.6,0.5]",
                                            "lights.0.intensity=[1,2,3]", "camera.fov_y_deg=35",
                                            "lights.0.position=[0.45,0.6,0.5]"};
  for (const std::string& c : changes) one.set(c);
  all.setAll(changes);
  EXPECT_EQ(all.document(), one.document());
  EXPECT_EQ(all.scene().lights[0].position, Vec3(0.45f, 0.6f, 0.5f));
  EXPECT_EQ(all.scene().camera.fovYDeg, 35.0f);
  EXPECT_TRUE(all.render().stats.extra.at("density_reused").get<bool>());
  const Json before = all.document();
  const Vec3 light = all.scene().lights[0].position;
  for (const std::vector<std::string>& bad :
       {std::vector<std::string>{"lights.0.position=[0.1,0.1,0.1]", "lights.3.position=[0,0,0]"},
        std::vector<std::string>{"lights.0.position=[0.1,0.1,0.1]", "lights.0.intensity=[2,2,2]",
                                 "render.nonsense=1"},
        std::vector<std::string>{"camera.width=64", "lights=[]", "lights.0=5"}}) {
    EXPECT_THROW(all.setAll(bad), ConfigError) << bad.back();
    EXPECT_EQ(all.document(), before) << bad.back();
    EXPECT_EQ(all.scene().lights[0].position, light);
    EXPECT_EQ(all.scene().camera.width, 32);
  }
  EXPECT_TRUE(all.render().stats.extra.at("density_reused").get<bool>());
}

// The typed setters (issue 36: what an engine calls per frame) are the string setters with the
// scene format's keys: the same scene, the same image as a fresh render, the same errors.
TEST(Renderer, TypedSettersAreTheStringSetters) {
  initialize();
  Renderer typed(blobDoc(), ".", "gradient", "cpu"), strings(blobDoc(), ".", "gradient", "cpu");
  typed.render();
  strings.render();
  Light spot;
  spot.type = Light::Type::Spot;
  spot.position = Vec3(0.5f, 1.4f, 0.5f);
  spot.direction = Vec3(0.0f, -1.0f, 0.0f);
  spot.intensity = Vec3(4.0f, 3.0f, 2.0f);
  spot.cosOuter = std::cos(glm::radians(30.0f));
  spot.cosInner = std::cos(glm::radians(20.0f));
  typed.setLight(0, spot);
  strings.set(
      R"(lights.0={"type": "spot", "position": [0.5, 1.4, 0.5], "direction": [0, -1, 0],
                   "intensity": [4, 3, 2], "outer_deg": 30, "inner_deg": 20})");
  Camera cam = typed.scene().camera;
  cam.position = Vec3(0.6f, 0.5f, -1.8f);
  cam.fovYDeg = 35.0f;
  typed.setCamera(cam);
  strings.set("camera.position=[0.6,0.5,-1.8]");
  strings.set("camera.fov_y_deg=35");
  const Light& a = typed.scene().lights[0];
  const Light& b = strings.scene().lights[0];
  EXPECT_EQ(a.position, b.position);
  EXPECT_EQ(a.intensity, b.intensity);
  EXPECT_EQ(a.direction, b.direction);
  EXPECT_NEAR(a.cosOuter, b.cosOuter, 1e-6f);  // degrees rounded to 1e-4° on the way
  EXPECT_NEAR(a.cosInner, b.cosInner, 1e-6f);
  EXPECT_EQ(typed.scene().camera.position, strings.scene().camera.position);
  EXPECT_EQ(typed.scene().camera.fovYDeg, 35.0f);
  const RenderResult t = typed.render(), s = strings.render();
  EXPECT_TRUE(t.stats.extra.at("density_reused").get<bool>());
  EXPECT_EQ(maxAbsDiff(t.image, s.image), 0.0);  // measured 0: the cones agree within 1e-6
  // Errors as for set(): named, and the renderer keeps its scene.
  try {
    typed.setLight(3, spot);
    ADD_FAILURE() << "set a light that does not exist";
  } catch (const ConfigError& e) {
    EXPECT_NE(std::string(e.what()).find("lights[3] does not exist"), std::string::npos)
        << e.what();
  }
  Camera bad = cam;
  bad.width = 0;
  EXPECT_THROW(typed.setCamera(bad), ConfigError);
  Light far = spot;
  far.intensity = Vec3(-1.0f);
  EXPECT_THROW(typed.setLight(0, far), ConfigError);
  EXPECT_EQ(typed.scene().camera.width, 32);
  EXPECT_EQ(typed.scene().lights[0].intensity, spot.intensity);
}

}  // namespace
}  // namespace scatterlab
