/// Scene objects through the `scatterlab` tool: every bad object gives one clear error naming
/// the object's index and key, a non-zero exit code, and no output file; a good scene with a
/// mesh renders.

#include <gtest/gtest.h>
#include <unistd.h>

#include <array>
#include <cstdio>
#include <filesystem>
#include <fstream>

#include "api/scatterlab.h"
#include "support/cli.h"

namespace fs = std::filesystem;
using scatterlab::Json;

namespace {

using scatterlab::testing::run;
using scatterlab::testing::RunResult;

class ObjectsCli : public scatterlab::testing::TempDirTest {
 protected:
  ObjectsCli() : TempDirTest("scatterlab_objects") {}

  /// A tiny scene holding `objects`.
  std::string scene(const Json& objects, const Json& lights = nullptr) const {
    Json doc = Json::parse(R"({
      "medium": {"bounds": {"min": [0,0,0], "max": [1,1,1]},
                 "density": {"type": "uniform", "value": 1}, "resolution": 8, "sigma_t": 1},
      "lights": [{"type": "point", "position": [0.5,1.4,0.5], "intensity": [4,4,4]}],
      "camera": {"position": [0.5,0.5,-2], "look_at": [0.5,0.5,0.5], "width": 8, "height": 6}})");
    doc["objects"] = objects;
    if (!lights.is_null()) doc["lights"] = lights;
    return write("scene.json", doc.dump());
  }
  /// Renders and expects failure with every string of `expected` in the message, and no image.
  void expectError(const Json& objects, const std::vector<std::string>& expected,
                   const std::string& extra = "") {
    const std::string out = (dir_ / "out.exr").string();
    const RunResult r = run("render " + scene(objects) + " -o " + out + " " + extra);
    EXPECT_NE(r.code, 0) << r.output;
    for (const std::string& e : expected)
      EXPECT_NE(r.output.find(e), std::string::npos) << "missing '" << e << "' in: " << r.output;
    EXPECT_FALSE(fs::exists(out)) << r.output;
  }
};

const Json kSphere = {{"type", "sphere"}, {"center", {0.5, 0.5, 0.5}}, {"radius", 0.2}};

}  // namespace

TEST_F(ObjectsCli, UnknownTypeNamesTheObjectAndTheAllowedTypes) {
  expectError(Json::array({kSphere, {{"type", "cone"}}}),
              {"objects[1].type", "cone", "sphere", "box", "mesh"});
}

TEST_F(ObjectsCli, NegativeRadius) {
  Json bad = kSphere;
  bad["radius"] = -1;
  expectError(Json::array({kSphere, bad}), {"objects[1].radius", "-1"});
}

TEST_F(ObjectsCli, BoxMinAboveMax) {
  expectError(Json::array({{{"type", "box"}, {"min", {0, 0, 0}}, {"max", {1, -1, 1}}}}),
              {"objects[0].max", "must exceed min"});
}

TEST_F(ObjectsCli, UnknownKeyAndKeyOfAnotherType) {
  Json bad = kSphere;
  bad["colour"] = {1, 0, 0};
  expectError(Json::array({bad}), {"objects[0]", "colour"});
  bad = kSphere;
  bad["min"] = {0, 0, 0};  // a box's key on a sphere
  expectError(Json::array({bad}), {"objects[0]", "min"});
}

TEST_F(ObjectsCli, AlbedoOutOfRange) {
  Json bad = kSphere;
  bad["albedo"] = {0.5, 1.5, 0.5};
  expectError(Json::array({bad}), {"objects[0].albedo"});
}

TEST_F(ObjectsCli, MissingObj) {
  expectError(Json::array({{{"type", "mesh"}, {"file", "nowhere.obj"}}}),
              {"objects[0].file", "nowhere.obj"});
}

TEST_F(ObjectsCli, BadMeshes) {
  const std::vector<std::pair<std::string, std::vector<std::string>>> cases = {
      {"v nan 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n", {"line 1", "not a finite number"}},
      {"v 0 0 0\nv 1 0 0\nv 0 1 1e999\nf 1 2 3\n", {"line 3", "not a finite number"}},
      {"v 0 0 0\nv 1 0 0\n", {"holds no triangles"}},
      {"v 0 0 0\nv 1 0 0\nl 1 2\n", {"holds no triangles"}},
      {"v 0 0 0\nv 1 0 0\nf 1 2 3\n", {"face 1", "vertex that does not exist"}},
      {"v 0 0 0\nf a b c\n", {"malformed OBJ"}},
  };
  for (const auto& [text, expected] : cases) {
    write("m.obj", text);
    std::vector<std::string> all = expected;
    all.push_back("objects[1].file");
    expectError(Json::array({kSphere, {{"type", "mesh"}, {"file", "m.obj"}}}), all);
  }
}

TEST_F(ObjectsCli, TransformScaleMustBePositive) {
  write("t.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n");
  expectError(Json::array({{{"type", "mesh"}, {"file", "t.obj"}, {"transform", {{"scale", 0}}}}}),
              {"objects[0].transform.scale"});
  expectError(
      Json::array({{{"type", "mesh"}, {"file", "t.obj"}, {"transform", {{"rotate", {0, 90, 0}}}}}}),
      {"objects[0].transform", "rotate"});
}

TEST_F(ObjectsCli, GpuBackendRefusesSupersampling) {
  // Objects render on the GPU (tests/gpu/test_objects.cpp); camera.spp > 1 does not yet.
  expectError(Json::array({kSphere}), {"camera.spp > 1 is not supported on the GPU backend yet"},
              "--method gradient --backend gpu --set camera.spp=4");
}

TEST_F(ObjectsCli, SppMustBeASquare) {
  const std::string out = (dir_ / "out.exr").string();
  const RunResult r =
      run("render " + scene(Json::array({kSphere})) + " -o " + out + " --set camera.spp=5");
  EXPECT_NE(r.code, 0);
  EXPECT_NE(r.output.find("camera.spp"), std::string::npos) << r.output;
  EXPECT_FALSE(fs::exists(out));
}

TEST_F(ObjectsCli, MeshWithMaterialsRenders) {
  // Two triangles in front of the box, each with its own .mtl diffuse colour (red, blue); the
  // light and camera are on the same side, so the pixel at the centre is red or blue only.
  write("m.mtl", "newmtl red\nKd 1 0 0\nnewmtl blue\nKd 0 0 1\n");
  write("m.obj",
        "mtllib m.mtl\nv -1 -1 -0.5\nv 2 -1 -0.5\nv 2 2 -0.5\nv -1 2 -0.5\n"
        "usemtl red\nf 1 2 3\nusemtl blue\nf 1 3 4\n");
  const std::string out = (dir_ / "out.exr").string();
  const Json light =
      Json::array({{{"type", "point"}, {"position", {0.5, 0.5, -1.5}}, {"intensity", {1, 1, 1}}}});
  const RunResult r =
      run("render " +
          scene(Json::array({{{"type", "mesh"},
                              {"file", "m.obj"},
                              {"transform", {{"translate", {0, 0, 0}}, {"scale", 1}}}}}),
                light) +
          " -o " + out);
  ASSERT_EQ(r.code, 0) << r.output;
  ASSERT_TRUE(fs::exists(out)) << r.output;
  const scatterlab::Image img = scatterlab::readExr(out);
  bool red = false, blue = false;
  for (int y = 0; y < img.height(); ++y)
    for (int x = 0; x < img.width(); ++x) {
      const auto c = img.at(x, y);
      EXPECT_EQ(c.y, 0.0f);
      red |= c.x > 0.0f && c.z == 0.0f;
      blue |= c.z > 0.0f && c.x == 0.0f;
    }
  EXPECT_TRUE(red && blue);
}
