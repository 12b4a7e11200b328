/// The tool's animation and output-format options (issue 15): `render --frames A:B` with light
/// paths, `--set` into arrays, `-o` extensions, `--tonemap`; bad input writes nothing.

#include <gtest/gtest.h>
#include <unistd.h>

#include <algorithm>
#include <array>
#include <cmath>
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

class CliFrames : public scatterlab::testing::TempDirTest {
 protected:
  CliFrames() : TempDirTest("scatterlab_frames") {}

  /// A blob lit by a lamp moving from x = 0.25 to x = 0.75 over t in [0, 2] (exact in binary).
  static Json movingScene() {
    return Json::parse(R"({
      "medium": {"bounds": {"min": [0,0,0], "max": [1,1,1]},
                 "density": {"type": "gaussians", "blobs": [{"center": [0.5,0.5,0.5], "radius": 0.25, "weight": 1.0}]},
                 "resolution": 16, "sigma_t": 4.0, "albedo": 0.6},
      "lights": [{"type": "point", "intensity": [4,4,4],
                  "path": [{"t": 0, "position": [0.25,1.3,0.5]}, {"t": 2, "position": [0.75,1.3,0.5]}]}],
      "camera": {"position": [0.5,0.5,-2], "look_at": [0.5,0.5,0.5], "width": 16, "height": 12},
      "render": {"method": "per-voxel"}})");
  }
  std::string writeScene(const Json& j) const { return write("scene.json", j.dump(2)); }
  /// No file in the directory but the scene.
  void expectNothingWritten() const {
    for (const auto& e : fs::directory_iterator(dir_))
      EXPECT_EQ(e.path().filename(), "scene.json") << e.path();
  }
};

}  // namespace

TEST_F(CliFrames, FramesFollowTheLightPath) {
  const std::string scene = writeScene(movingScene());
  const RunResult r = run("render " + scene + " -o " + out("f.exr") + " --stats " + out("f.json") +
                          " --frames 0:2 --fps 1 --backend cpu");
  ASSERT_EQ(r.code, 0) << r.output;
  for (int f = 0; f <= 2; ++f) {
    const std::string n = "f.000" + std::to_string(f);
    ASSERT_TRUE(fs::exists(out(n + ".exr"))) << n;
    const Json st = Json::parse(std::ifstream(out(n + ".json")));
    EXPECT_EQ(st["frame"], f);
    EXPECT_DOUBLE_EQ(st["time"].get<double>(), f);
    EXPECT_EQ(st["density_reused"], f > 0);  // the still medium is built once
  }
  // Frame 1 (t = 1) is the scene with the lamp half-way, rendered on its own.
  Json half = movingScene();
  half["lights"][0].erase("path");
  half["lights"][0]["position"] = {0.5, 1.3, 0.5};
  const fs::path p = dir_ / "half.json";
  std::ofstream(p) << half.dump();
  ASSERT_EQ(run("render " + p.string() + " -o " + out("half.exr") + " --backend cpu").code, 0);
  const scatterlab::ImageError e = scatterlab::compareImages(scatterlab::readExr(out("f.0001.exr")),
                                                             scatterlab::readExr(out("half.exr")));
  EXPECT_EQ(e.maxAbs, 0.0);
  EXPECT_GT(scatterlab::compareImages(scatterlab::readExr(out("f.0000.exr")),
                                      scatterlab::readExr(out("half.exr")))
                .relL2,
            0.01);  // and the lamp did move
}

TEST_F(CliFrames, BadFrameRangesAreUsageErrors) {
  const std::string scene = writeScene(movingScene());
  for (const char* bad : {"3:1", "1-4", "a:b", ":4", "2:", "0:100000"}) {
    const RunResult r = run("render " + scene + " -o " + out("f.exr") + " --frames " + bad);
    EXPECT_EQ(r.code, 2) << bad << ": " << r.output;
    EXPECT_NE(r.output.find("--frames"), std::string::npos) << r.output;
    EXPECT_NE(r.output.find("is not a frame range"), std::string::npos) << r.output;
  }
  expectNothingWritten();
}

TEST_F(CliFrames, BadPathAndIndexNameTheKey) {
  Json bad = movingScene();
  bad["lights"][0]["path"][1]["t"] = 0;
  RunResult r = run("render " + writeScene(bad) + " -o " + out("f.exr") + " --frames 0:2");
  EXPECT_EQ(r.code, 1) << r.output;
  EXPECT_NE(r.output.find("lights[0].path[1].t"), std::string::npos) << r.output;
  expectNothingWritten();
  r = run("render " + writeScene(movingScene()) + " -o " + out("f.exr") +
          " --set lights.1.intensity=2");
  EXPECT_EQ(r.code, 1) << r.output;
  EXPECT_NE(r.output.find("index 1 out of range: 'lights' has 1 element"), std::string::npos)
      << r.output;
  expectNothingWritten();
}

TEST_F(CliFrames, OutputExtensionDecidesTheFormat) {
  const std::string scene = writeScene(movingScene());
  RunResult r = run("render " + scene + " -o " + out("f.tif"));
  EXPECT_EQ(r.code, 2) << r.output;
  EXPECT_NE(r.output.find("unknown extension: expected .exr or .png"), std::string::npos)
      << r.output;
  expectNothingWritten();
  r = run("render " + scene + " -o " + out("f.PNG") + " --tonemap aces");
  ASSERT_EQ(r.code, 0) << r.output;
  std::ifstream png(out("f.PNG"), std::ios::binary);
  char sig[8] = {};
  png.read(sig, 8);
  EXPECT_EQ(std::string(sig + 1, 3), "PNG");
  r = run("render " + scene + " -o " + out("g.exr") + " --tonemap reinhard");
  EXPECT_EQ(r.code, 2) << r.output;
  EXPECT_NE(r.output.find("--tonemap"), std::string::npos) << r.output;
}

TEST_F(CliFrames, InfoReadsPngAndPrintsJson) {
  const std::string scene = writeScene(movingScene());
  ASSERT_EQ(run("render " + scene + " -o " + out("i.exr") + " --png " + out("i.png") + " -q").code,
            0);
  const scatterlab::Image exr = scatterlab::readExr(out("i.exr"));
  // The PNG's mean red as writePng quantises it with the default curve, ACES (issue 25):
  // floor(sRGB(aces(v))·255 + 0.5) / 255.
  double pngRed = 0.0, exrRed = 0.0;
  for (const scatterlab::Vec3& p : exr.pixels()) {
    const float aces = scatterlab::toneCurve(p.x, scatterlab::ToneCurve::Aces);
    pngRed += std::floor(scatterlab::toneMapSrgb(aces) * 255.0f + 0.5f) / 255.0;
    exrRed += p.x;
  }
  pngRed /= double(exr.pixels().size());
  exrRed /= double(exr.pixels().size());

  RunResult r = run("info " + out("i.png") + " --json");
  ASSERT_EQ(r.code, 0) << r.output;
  Json j = Json::parse(r.output);
  EXPECT_EQ(j["kind"], "image");
  EXPECT_EQ(j["format"], "PNG");
  EXPECT_EQ(j["width"], 16);
  EXPECT_EQ(j["height"], 12);
  EXPECT_EQ(j["bit_depth"], 8);
  EXPECT_NEAR(j["mean"][0].get<double>(), pngRed, 1e-6);

  r = run("info " + out("i.exr") + " --json");
  ASSERT_EQ(r.code, 0) << r.output;
  j = Json::parse(r.output);
  EXPECT_EQ(j["format"], "OpenEXR");
  EXPECT_EQ(j["channels"], "RGBA");  // A = 1 - transmittance (tests/api/test_compositing.cpp)
  EXPECT_NEAR(j["mean"][0].get<double>(), exrRed, 1e-6 * std::max(1.0, exrRed));

  r = run("info " + scene + " --json");
  ASSERT_EQ(r.code, 0) << r.output;
  j = Json::parse(r.output);
  EXPECT_EQ(j["kind"], "scene");
  EXPECT_EQ(j["camera"]["width"], 16);
  EXPECT_EQ(j["lights"][0]["type"], "point");

  r = run("info " + out("i.png"));  // the text form names the format
  EXPECT_NE(r.output.find("16x12 PNG, 8-bit RGB"), std::string::npos) << r.output;
}
