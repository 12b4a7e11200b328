#include <gtest/gtest.h>

#include "support/scenes.h"

using namespace scatterlab;
using scatterlab::testing::sceneFromJson;

namespace {

Json validDoc() {
  return Json::parse(R"({
    "medium": {"bounds": {"min": [0,0,0], "max": [1,1,1]},
               "density": {"type": "gaussians", "blobs": [{"center": [0.5,0.5,0.5], "radius": 0.2, "weight": 1.0}]},
               "resolution": 32, "sigma_t": 4.0, "albedo": 0.6, "phase": {"type": "isotropic"}},
    "lights": [{"type": "point", "position": [0.5,1.4,0.5], "intensity": [4,4,4]}],
    "camera": {"position": [0.5,0.5,-2], "look_at": [0.5,0.5,0.5], "up": [0,1,0], "fov_y_deg": 40,
               "width": 32, "height": 24},
    "background": [0,0,0],
    "render": {"method": "exact"}})");
}

/// Expects ConfigError whose message contains every fragment.
void expectConfigError(const Json& doc, std::initializer_list<std::string> fragments) {
  try {
    const Scene s = sceneFromJson(doc);
    createMethod(s);
    FAIL() << "no error for " << doc.dump();
  } catch (const ConfigError& e) {
    for (const auto& f : fragments)
      EXPECT_NE(std::string(e.what()).find(f), std::string::npos)
          << "message '" << e.what() << "' lacks '" << f << "'";
  }
}

}  // namespace

TEST(Scene, ParsesTheDocumentedExample) {
  const Scene s = sceneFromJson(validDoc());
  EXPECT_EQ(s.medium.resolution, IVec3(32));
  EXPECT_FLOAT_EQ(s.medium.sigmaT, 4.0f);
  EXPECT_FLOAT_EQ(s.medium.sigmaS(), 2.4f);
  EXPECT_EQ(s.medium.density->type(), "gaussians");
  EXPECT_FLOAT_EQ(s.medium.density->eval(Vec3(0.5f)), 1.0f);
  ASSERT_EQ(s.lights.size(), 1u);
  EXPECT_EQ(s.lights[0].position, Vec3(0.5f, 1.4f, 0.5f));
  EXPECT_EQ(s.camera.width, 32);
  EXPECT_NO_THROW(createMethod(s));
}

TEST(Scene, SpotAndDirectionalLights) {
  Json d = validDoc();
  d["lights"] = Json::parse(R"([
    {"type": "spot", "position": [0.5,1.2,0.5], "direction": [0,-2,0], "intensity": 3,
     "inner_deg": 10, "outer_deg": 20},
    {"type": "directional", "direction": [1,-1,0], "irradiance": [1,2,3]}])");
  const Scene s = sceneFromJson(d);
  EXPECT_EQ(s.lights[0].type, Light::Type::Spot);
  EXPECT_EQ(s.lights[0].direction, Vec3(0, -1, 0));
  EXPECT_EQ(s.lights[0].intensity, Vec3(3));
  EXPECT_NEAR(s.lights[0].cosOuter, std::cos(20 * kPi / 180), 1e-6);
  EXPECT_EQ(s.lights[1].type, Light::Type::Directional);
  EXPECT_NEAR(s.lights[1].direction.x, std::sqrt(0.5f), 1e-6);
}

TEST(Scene, OverridesByDottedPath) {
  Json d = validDoc();
  applyOverride(d, "camera.width=640");
  applyOverride(d, "render.sampler.count=512");
  applyOverride(d, "render.method=per-voxel");
  applyOverride(d, "medium.phase={\"type\":\"hg\",\"g\":0.5}");
  EXPECT_EQ(d["camera"]["width"], 640);
  EXPECT_EQ(d["render"]["sampler"]["count"], 512);
  EXPECT_EQ(d["render"]["method"], "per-voxel");  // not JSON: taken as a string
  EXPECT_EQ(d["medium"]["phase"]["g"], 0.5);
  EXPECT_THROW(applyOverride(d, "camera.width.x=1"), ConfigError);  // 640 is not an object
  EXPECT_THROW(applyOverride(d, "novalue"), ConfigError);
  EXPECT_THROW(applyOverride(d, "a..b=1"), ConfigError);
}

/// Message of the ConfigError `f` throws ("" when it throws none).
template <class F>
std::string configMessage(F f) {
  try {
    f();
  } catch (const ConfigError& e) {
    return e.what();
  }
  return "";
}

TEST(Scene, OverridesIndexArrays) {
  Json d = validDoc();
  ASSERT_EQ(d["lights"].size(), 1u);
  applyOverride(d, "lights.0.intensity=[1,2,3]");
  applyOverride(d, "lights.0.position.2=0.25");
  EXPECT_EQ(d["lights"][0]["intensity"], Json::parse("[1,2,3]"));
  EXPECT_EQ(d["lights"][0]["position"][2], 0.25);
  const Scene s = sceneFromJson(d);
  EXPECT_FLOAT_EQ(s.lights[0].position.z, 0.25f);
  // Out of range, not an index, and a key below a number: each names the path.
  EXPECT_NE(configMessage([&] {
              applyOverride(d, "lights.1.position=[0,0,0]");
            }).find("index 1 out of range: 'lights' has 1 element"),
            std::string::npos);
  EXPECT_NE(configMessage([&] {
              applyOverride(d, "lights.first.position=[0,0,0]");
            }).find("'lights' is an array of 1; 'first' is not an element index"),
            std::string::npos);
  EXPECT_NE(configMessage([&] {
              applyOverride(d, "lights.0.position.2.x=1");
            }).find("'lights.0.position.2' is not an object or an array"),
            std::string::npos);
  EXPECT_EQ(d["lights"].size(), 1u);  // nothing appended
}

TEST(Scene, BadInputsNameKeyValueAndAllowed) {
  Json d;
  d = validDoc();
  d["medium"]["colour"] = 1;
  expectConfigError(d, {"medium.colour", "unknown key", "sigma_t"});
  d = validDoc();
  d["render"]["step_size"] = 1;
  expectConfigError(d, {"render.step_size", "unknown key", "march_step"});
  d = validDoc();
  d["medium"].erase("density");
  expectConfigError(d, {"medium.density", "missing"});
  d = validDoc();
  d.erase("camera");
  expectConfigError(d, {"camera", "missing"});
  d = validDoc();
  d["medium"]["sigma_t"] = "four";
  expectConfigError(d, {"medium.sigma_t", "expected a number", "\"four\""});
  d = validDoc();
  d["medium"]["sigma_t"] = -1;
  expectConfigError(d, {"medium.sigma_t", "-1", ">= 0"});
  d = validDoc();
  d["medium"]["albedo"] = 1.5;
  expectConfigError(d, {"medium.albedo", "1.5", "[0, 1]"});
  d = validDoc();
  d["camera"]["fov_y_deg"] = 180;
  expectConfigError(d, {"camera.fov_y_deg", "180", "(0, 180)"});
  d = validDoc();
  d["camera"]["fov_y_deg"] = 0;
  expectConfigError(d, {"camera.fov_y_deg", "(0, 180)"});
  d = validDoc();
  d["medium"]["resolution"] = 0;
  expectConfigError(d, {"medium.resolution", "[1, 4096]"});
  d = validDoc();
  d["medium"]["resolution"] = 2000;
  expectConfigError(d, {"medium.resolution", "memory bound"});
  d = validDoc();
  d["medium"]["resolution"] = {64, 64, 64.5};
  expectConfigError(d, {"medium.resolution", "integers"});
  d = validDoc();
  d["medium"]["density"]["type"] = "fractal";
  expectConfigError(d, {"medium.density.type", "fractal", "'gaussians'", "'uniform'"});
  d = validDoc();
  d["lights"][0]["type"] = "area";
  expectConfigError(d, {"lights[0].type", "area", "'spot'"});
  d = validDoc();
  d["lights"][0]["position"] = {1, 2};
  expectConfigError(d, {"lights[0].position", "3 numbers"});
  d = validDoc();
  d["lights"][0]["intensity"] = -2;
  expectConfigError(d, {"lights[0].intensity", "-2", "allowed: [0, 1e+20]"});
  d = validDoc();
  d["medium"]["phase"] = {{"type", "hg"}, {"g", 1.0}};
  expectConfigError(d, {"medium.phase.g", "(-1, 1)"});
  d = validDoc();
  d["render"]["method"] = "magic";
  expectConfigError(d, {"render.method", "magic", "'exact'", "'per-voxel'"});
  d = validDoc();
  d["medium"]["bounds"]["max"] = {1, 0, 1};
  expectConfigError(d, {"medium.bounds.max", "exceed min"});
  d = validDoc();
  d["camera"]["look_at"] = d["camera"]["position"];
  expectConfigError(d, {"camera.look_at"});
  d = validDoc();
  d["lights"] = Json::object();
  expectConfigError(d, {"lights", "expected an array"});
  d = validDoc();
  d["medium"]["density"]["blobs"][0]["radius"] = 0;
  expectConfigError(d, {"medium.density.blobs[0].radius", "> 0"});
  d = validDoc();
  d["render"]["march_step"] = 0;
  expectConfigError(d, {"render.march_step"});
}

TEST(Scene, GridDensityInlineAndFileErrors) {
  Json d = validDoc();
  d["medium"]["density"] =
      Json::parse(R"({"type": "grid", "dims": [2,1,1], "values": [0.5, 1.5]})");
  const Scene s = sceneFromJson(d);
  EXPECT_NEAR(s.medium.density->eval(Vec3(0.25f, 0.5f, 0.5f)), 0.5f, 1e-6);
  EXPECT_NEAR(s.medium.density->eval(Vec3(0.5f, 0.5f, 0.5f)), 1.0f, 1e-6);
  d["medium"]["density"]["values"] = {0.5};
  expectConfigError(d, {"medium.density.values", "2 numbers"});
  d["medium"]["density"] =
      Json::parse(R"({"type": "grid", "dims": [2,1,1], "file": "no-such.raw"})");
  try {
    sceneFromJson(d);
    FAIL();
  } catch (const IoError& e) {
    EXPECT_NE(std::string(e.what()).find("no-such.raw"), std::string::npos);
    EXPECT_NE(std::string(e.what()).find("does not exist"), std::string::npos);
  }
}

TEST(Scene, MethodOverrideToleratesTheFilesOwnKeys) {
  Json d = validDoc();
  d["render"] = {{"method", "per-voxel"}, {"radiance_resolution", 16}};
  const Scene s = sceneFromJson(d);
  EXPECT_NO_THROW(createMethod(s, "exact"));
  d["render"]["bogus"] = 1;
  EXPECT_THROW(createMethod(sceneFromJson(d), "exact"), ConfigError);
}

TEST(Scene, MethodOverrideWithoutRenderObject) {
  Json d = validDoc();
  d.erase("render");
  const Scene s = sceneFromJson(d);
  EXPECT_NO_THROW(createMethod(s, "per-voxel"));
  EXPECT_NO_THROW(createMethod(s));
}
