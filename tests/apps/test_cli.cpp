/// The `scatterlab` tool end to end: good runs write complete outputs; bad input gives one clear
/// message, a non-zero exit code, and no output file.

#include <gtest/gtest.h>
#include <unistd.h>

#include <array>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>

#include "api/scatterlab.h"
#include "cpu/sample_view.h"
#include "support/cli.h"

namespace fs = std::filesystem;
using scatterlab::Json;

namespace {

using scatterlab::testing::run;
using scatterlab::testing::RunResult;

class Cli : public scatterlab::testing::TempDirTest {
 protected:
  Cli() : TempDirTest("scatterlab_cli") {}

  static Json tinyScene() { return Json::parse(scatterlab::testing::kTinySceneJson); }
  std::string writeScene(const Json& j) const { return write("scene.json", j.dump(2)); }

  /// Runs a render expected to fail; checks exit code, message fragments, and no outputs.
  void expectRenderFails(const std::string& scene, std::initializer_list<std::string> fragments,
                         const std::string& extra = "") {
    const std::string exr = out("o.exr"), png = out("o.png"), stats = out("o.json");
    const RunResult r =
        run("render " + scene + " -o " + exr + " --png " + png + " --stats " + stats + " " + extra);
    EXPECT_NE(r.code, 0) << r.output;
    for (const auto& f : fragments)
      EXPECT_NE(r.output.find(f), std::string::npos)
          << "output '" << r.output << "' lacks '" << f << "'";
    EXPECT_FALSE(fs::exists(exr));
    EXPECT_FALSE(fs::exists(png));
    EXPECT_FALSE(fs::exists(stats));
    for (const auto& e : fs::directory_iterator(dir_))
      EXPECT_EQ(e.path().filename().string().find(".tmp"), std::string::npos) << e.path();
  }
};

}  // namespace

TEST_F(Cli, RenderWritesImageStatsAndHonoursSet) {
  const std::string scene = writeScene(tinyScene());
  const RunResult r =
      run("render " + scene + " -o " + out("a.exr") + " --png " + out("a.png") + " --stats " +
          out("a.json") + " --set camera.width=20 --set render.march_step=0.01");
  ASSERT_EQ(r.code, 0) << r.output;
  const Json stats = Json::parse(std::ifstream(out("a.json")));
  EXPECT_EQ(stats["method"], "exact");
  EXPECT_EQ(stats["backend"], "cpu");
  EXPECT_EQ(stats["width"], 20);
  EXPECT_EQ(stats["height"], 12);
  EXPECT_FALSE(stats["device"].get<std::string>().empty());
  EXPECT_TRUE(stats["timings_ms"].contains("total"));
  EXPECT_TRUE(stats["timings_ms"].contains("march"));
  EXPECT_DOUBLE_EQ(stats["march_step"].get<double>(), 0.01f);
  // The process's peak resident memory: the tool's own pages at least (the glow's 128³ frame
  // measured 50 MiB, fig3 gradient at 256³ 615 MiB).
  EXPECT_GT(stats["peak_host_mib"].get<double>(), 1.0);
  EXPECT_LT(stats["peak_host_mib"].get<double>(), 2048.0);
  const scatterlab::Image img = scatterlab::readExr(out("a.exr"));
  EXPECT_EQ(img.width(), 20);
  EXPECT_GT(img.at(10, 6).x, 0.0f);
  EXPECT_TRUE(fs::exists(out("a.png")));
  EXPECT_NE(r.output.find(out("a.exr")), std::string::npos);
}

// Issue 25: `--samples-png` on a scene where nothing splits (gradient: the initial samples only)
// drew every sample as a 2-px white disc, and the thousands projected through the volume painted
// a solid white block. The dots are sized (and, where dense, made translucent) to cover at most
// kSampleCover of the area the samples project to.
TEST_F(Cli, SamplesPngWithoutSplitsDrawsDotsNotASolidBlock) {
  using scatterlab::dotStyle;
  using scatterlab::kSampleCover;
  EXPECT_EQ(dotStyle(100, 10000).radius, 2);  // sparse: the full 2-px discs
  EXPECT_EQ(dotStyle(100, 10000).opacity, 1.0f);
  EXPECT_EQ(dotStyle(512, 9500).radius, 1);  // 512 × 13 px would cover 70 %
  EXPECT_EQ(dotStyle(512, 9500).opacity, 1.0f);
  const auto dense = dotStyle(2000, 1500);  // more samples than pixels: translucent pixels
  EXPECT_EQ(dense.radius, 0);
  EXPECT_NEAR(dense.opacity, kSampleCover * 1500 / 2000, 1e-6);
  const std::string scene = std::string(SCATTERLAB_SOURCE_DIR) + "/data/scenes/shaft.json";
  RunResult r = run("render " + scene +
                    " --method gradient --backend cpu --set camera.width=64 --set "
                    "camera.height=48 -o " +
                    out("s.exr") + " --samples-png " + out("s.png") + " -q");
  ASSERT_EQ(r.code, 0) << r.output;
  r = run("info " + out("s.png") + " --json");
  ASSERT_EQ(r.code, 0) << r.output;
  const Json j = Json::parse(r.output);
  // The samples' square covers about half of the image; filled white it averaged 0.50 (measured
  // 2026-11-26), now 0.28. The dots are still there at full brightness (the PNG curve shows 1 as
  // about 0.9).
  EXPECT_LT(j["mean"][0].get<double>(), 0.39) << j.dump();
  EXPECT_GT(j["max"][0].get<double>(), 0.8) << j.dump();
}

// The method layer's three user-visible rules, through the tool (issue #10's failures).
TEST_F(Cli, MethodOverrideBackendKeysAndResolutions) {
  const std::string scene = writeScene(tinyScene());  // its own method is `exact`
  // --method X means --set render.method=X: the sampler key is the gradient method's.
  const RunResult a = run("render " + scene + " -q -o " + out("a.exr") +
                          " --method gradient --set render.sampler.count=3");
  ASSERT_EQ(a.code, 0) << a.output;
  const RunResult b = run("render " + scene + " -q -o " + out("b.exr") +
                          " --set render.method=gradient --set render.sampler.count=3");
  ASSERT_EQ(b.code, 0) << b.output;
  EXPECT_EQ(scatterlab::readExr(out("a.exr")).pixels(), scatterlab::readExr(out("b.exr")).pixels());
  // A key of another method is ignored with one warning; a key nobody reads is an error.
  const RunResult c = run("render " + scene + " -q -o " + out("c.exr") +
                          " --set render.sampler.count=3 --set render.epsilon=0.1");
  ASSERT_EQ(c.code, 0) << c.output;
  EXPECT_NE(c.output.find("warning: ignoring 'render.epsilon', 'render.sampler'"),
            std::string::npos)
      << c.output;
  const RunResult d = run("render " + scene + " -q -o " + out("d.exr") + " --set render.sampels=3");
  EXPECT_EQ(d.code, 1);
  EXPECT_NE(d.output.find("unknown key 'render.sampels'"), std::string::npos) << d.output;
  EXPECT_FALSE(fs::exists(out("d.exr")));
  // A GPU-only key is valid on the CPU and reported unused there.
  const RunResult e =
      run("render " + scene + " -q -o " + out("e.exr") + " --stats " + out("e.json") +
          " --method per-voxel --backend cpu --set render.slicing=view-planes");
  ASSERT_EQ(e.code, 0) << e.output;
  const Json stats = Json::parse(std::ifstream(out("e.json")));
  EXPECT_EQ(stats["unused_keys"], Json::array({"render.slicing"}));
  // Every resolution key follows one rule.
  const RunResult f = run("render " + scene + " -q -o " + out("f.exr") +
                          " --method per-voxel --set 'render.radiance_resolution=[8,8,8.7]'");
  EXPECT_EQ(f.code, 1);
  EXPECT_NE(f.output.find("'render.radiance_resolution': expected integers"), std::string::npos)
      << f.output;
  EXPECT_FALSE(fs::exists(out("f.exr")));
}

TEST_F(Cli, CompareReportsErrorsAsJson) {
  const std::string scene = writeScene(tinyScene());
  ASSERT_EQ(run("render " + scene + " -q -o " + out("ref.exr")).code, 0);
  ASSERT_EQ(run("render " + scene + " -q -o " + out("pv.exr") + " --method per-voxel").code, 0);
  RunResult r = run("compare " + out("ref.exr") + " " + out("ref.exr") + " --json");
  ASSERT_EQ(r.code, 0) << r.output;
  Json j = Json::parse(r.output);
  EXPECT_EQ(j["rel_l2"], 0.0);
  EXPECT_EQ(j["psnr_db"], "inf");
  r = run("compare " + out("pv.exr") + " " + out("ref.exr") + " --json");
  ASSERT_EQ(r.code, 0) << r.output;
  j = Json::parse(r.output);
  EXPECT_GT(j["rel_l2"].get<double>(), 0.0);
  // Per-voxel against exact on the tiny scene: measured 0.00627 (2026-11-23); ×1.5.
  EXPECT_LT(j["rel_l2"].get<double>(), 0.0094);
  r = run("compare " + out("pv.exr") + " " + out("missing.exr"));
  EXPECT_NE(r.code, 0);
  EXPECT_NE(r.output.find("missing.exr"), std::string::npos);
}

// The masked relative L2 and the visibly wrong share, on hand-made 16×12 images. The tiny
// scene's light at (0.5, 1.4, 0.5) projects to (8, 0.066) px (camera 2.5 in front of it, 0.9
// above the axis, tan 20° = 0.364): within 1 px of it lie the pixel centres (7.5, 0.5) and
// (8.5, 0.5) (0.66 px away; the next ones are 1.5 px away); within 2 px (the default radius:
// 1% of the 20-px diagonal is raised to 2) also (6.5|9.5, 0.5) and (7.5|8.5, 1.5): 6 pixels.
TEST_F(Cli, CompareMasksTheLightsOfTheScene) {
  const std::string scene = writeScene(tinyScene());
  scatterlab::Image ref(16, 12), img(16, 12);
  for (auto& p : ref.pixels()) p = scatterlab::Vec3(1.0f);
  img = ref;
  img.at(8, 0) = scatterlab::Vec3(11.0f);  // next to the light: 100 of the 101 squared error
  img.at(0, 11) = scatterlab::Vec3(0.0f);  // far from it
  scatterlab::writeExr(ref, out("ref.exr"));
  scatterlab::writeExr(img, out("img.exr"));
  const std::string images = out("img.exr") + " " + out("ref.exr");
  RunResult r = run("compare " + images + " --json --scene " + scene);
  ASSERT_EQ(r.code, 0) << r.output;
  Json j = Json::parse(r.output);
  EXPECT_NEAR(j["rel_l2"].get<double>(), std::sqrt(101.0 / 192.0), 1e-9);
  EXPECT_NEAR(j["masked_rel_l2"].get<double>(), std::sqrt(1.0 / 186.0), 1e-9);
  EXPECT_EQ(j["masked_pixels"], 6);
  EXPECT_EQ(j["mask_radius_px"], 2.0);
  EXPECT_EQ(j["masked_lights"], 1);
  // Pixel (8, 0): 11 and 1 both clamp to white, so only (0, 11) (black vs white) is visibly
  // wrong.
  EXPECT_NEAR(j["visibly_wrong"].get<double>(), 1.0 / 192.0, 1e-12);
  r = run("compare " + images + " --json --scene " + scene + " --mask-radius 1");
  ASSERT_EQ(r.code, 0) << r.output;
  j = Json::parse(r.output);
  EXPECT_NEAR(j["masked_rel_l2"].get<double>(), std::sqrt(1.0 / 190.0), 1e-9);
  EXPECT_EQ(j["masked_pixels"], 2);
  // Text: the radius is reported with the number; without --scene there is no masked line.
  r = run("compare " + images + " --scene " + scene);
  ASSERT_EQ(r.code, 0) << r.output;
  EXPECT_NE(r.output.find("masked rel. L2:    0.0733236 (7.332%), 6 px within 2 px of 1 light"),
            std::string::npos)
      << r.output;
  EXPECT_NE(r.output.find("visibly wrong:     0.5208% of pixels"), std::string::npos) << r.output;
  r = run("compare " + images);
  ASSERT_EQ(r.code, 0) << r.output;
  EXPECT_EQ(r.output.find("masked"), std::string::npos) << r.output;
  // --set applies to the scene: the light moved behind the camera masks nothing.
  r = run("compare " + images + " --json --scene " + scene +
          " --set 'lights=[{\"type\": \"point\", \"position\": [0.5,0.5,-3], "
          "\"intensity\": 1}]'");
  ASSERT_EQ(r.code, 0) << r.output;
  j = Json::parse(r.output);
  EXPECT_EQ(j["masked_pixels"], 0);
  EXPECT_EQ(j["masked_rel_l2"], j["rel_l2"]);
}

TEST_F(Cli, CompareBadInputs) {
  const std::string scene = writeScene(tinyScene());
  scatterlab::writeExr(scatterlab::Image(16, 12), out("a.exr"));
  scatterlab::writeExr(scatterlab::Image(16, 12), out("b.exr"));
  const std::string images = out("a.exr") + " " + out("b.exr") + " --diff " + out("d.png");
  const auto expectFails = [&](const std::string& extra, int code,
                               std::initializer_list<std::string> fragments) {
    const RunResult r = run("compare " + images + " " + extra);
    EXPECT_EQ(r.code, code) << extra << ": " << r.output;
    for (const auto& f : fragments)
      EXPECT_NE(r.output.find(f), std::string::npos) << "'" << r.output << "' lacks '" << f << "'";
    EXPECT_FALSE(fs::exists(out("d.png"))) << extra;
  };
  // Usage errors: exit 2.
  expectFails("--mask-radius 3", 2, {"--mask-radius requires --scene"});
  expectFails("--set camera.width=8", 2, {"--set requires --scene"});
  expectFails("--scene " + scene + " --mask-radius -1", 2,
              {"--mask-radius", "expected a number of pixels >= 0, got '-1'"});
  expectFails("--scene " + scene + " --mask-radius wide", 2, {"--mask-radius", "'wide'"});
  // Issue 37: these fell back to the default scale silently (inf: a saturated map).
  for (const char* bad : {"nan", "-inf", "inf", "-1", "0", "1e-300", "''"})
    expectFails(std::string("--diff-scale ") + bad, 2,
                {"--diff-scale: expected a finite multiplier > 0, got '"});
  // Bad input: exit 1, one message naming it, no --diff output.
  expectFails("--scene " + out("nope.json"), 1, {"nope.json", "does not exist"});
  expectFails("--scene " + scene + " --set camera.width=20", 1,
              {"camera is 20x12 but the images are 16x12"});
  expectFails("--scene " + scene + " --set camera.zoom=2", 1, {"camera.zoom", "unknown key"});
}

TEST_F(Cli, InfoDescribesScenesAndImages) {
  const std::string scene = writeScene(tinyScene());
  RunResult r = run("info " + scene);
  ASSERT_EQ(r.code, 0) << r.output;
  EXPECT_NE(r.output.find("Gaussian"), std::string::npos);
  EXPECT_NE(r.output.find("16x16x16"), std::string::npos);
  ASSERT_EQ(run("render " + scene + " -q -o " + out("i.exr")).code, 0);
  r = run("info " + out("i.exr"));
  ASSERT_EQ(r.code, 0) << r.output;
  EXPECT_NE(r.output.find("16x12"), std::string::npos);
  // The header's attributes that render writes (issue 36): provenance and the camera matrices.
  EXPECT_NE(r.output.find("scatterlab:method: "), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("scatterlab:device: "), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("worldToCamera: ["), std::string::npos) << r.output;
  r = run("info --json " + out("i.exr"));
  ASSERT_EQ(r.code, 0) << r.output;
  const Json j = Json::parse(r.output);
  EXPECT_EQ(j["attributes"]["scatterlab:backend"], "cpu") << r.output;
  EXPECT_EQ(j["attributes"]["worldToNDC"].size(), 16u) << r.output;
  // Each light with what its type has, a spot's cone, a keyframed path.
  Json lit = tinyScene();
  lit["lights"] = Json::parse(R"([
      {"type": "point", "intensity": 1,
       "path": [{"t": 0, "position": [0.2, 1.5, 0.5]}, {"t": 2, "position": [0.8, 1.5, 0.5]}]},
      {"type": "spot", "position": [0.5, 1.6, 0.5], "direction": [0, -1, 0], "intensity": 2,
       "outer_deg": 30, "inner_deg": 20},
      {"type": "directional", "direction": [0, -1, 0], "irradiance": 3}])");
  r = run("info " + write("lit.json", lit.dump()));
  ASSERT_EQ(r.code, 0) << r.output;
  for (const char* want :
       {"lights[0]: point, position [0.2 1.5 0.5], intensity [1 1 1]; keyframed path of 2 keys, "
        "t 0 to 2",
        "lights[1]: spot, position [0.5 1.6 0.5], direction [0 -1 0], cone 30 deg (full inside "
        "20 deg), intensity [2 2 2]",
        "lights[2]: directional, direction [0 -1 0], irradiance [3 3 3]"})
    EXPECT_NE(r.output.find(want), std::string::npos) << want << "\n" << r.output;
  r = run("info " + write("x.txt", "hello"));
  EXPECT_NE(r.code, 0);
  EXPECT_NE(r.output.find("known extensions"), std::string::npos);
}

TEST_F(Cli, HelpOnEveryCommand) {
  for (const char* c : {"", "render ", "compare ", "info "}) {
    const RunResult r = run(std::string(c) + "--help");
    EXPECT_EQ(r.code, 0) << c;
    EXPECT_NE(r.output.find("Usage"), std::string::npos) << c;
  }
}

TEST_F(Cli, MalformedJson) {
  expectRenderFails(write("bad.json", "{\"medium\": {,}"), {"malformed JSON", "bad.json"});
}

TEST_F(Cli, MissingSceneFileAndDirectory) {
  expectRenderFails(out("nope.json"), {"nope.json", "does not exist"});
  expectRenderFails(dir_.string(), {"is a directory"});
}

TEST_F(Cli, UnknownKey) {
  Json s = tinyScene();
  s["camera"]["zoom"] = 2;
  expectRenderFails(writeScene(s), {"camera.zoom", "unknown key", "fov_y_deg"});
}

TEST_F(Cli, MissingRequiredKey) {
  Json s = tinyScene();
  s["camera"].erase("position");
  expectRenderFails(writeScene(s), {"camera.position", "missing"});
}

TEST_F(Cli, WrongType) {
  Json s = tinyScene();
  s["camera"]["width"] = "wide";
  expectRenderFails(writeScene(s), {"camera.width", "expected an integer", "\"wide\""});
}

TEST_F(Cli, OutOfRangeValues) {
  const std::string scene = writeScene(tinyScene());
  expectRenderFails(scene, {"medium.sigma_t", "-2", ">= 0"}, "--set medium.sigma_t=-2");
  expectRenderFails(scene, {"medium.albedo", "[0, 1]"}, "--set medium.albedo=1.2");
  expectRenderFails(scene, {"camera.fov_y_deg", "(0, 180)"}, "--set camera.fov_y_deg=190");
  expectRenderFails(scene, {"medium.resolution", "[1, 4096]"}, "--set medium.resolution=0");
  expectRenderFails(scene, {"medium.resolution", "memory bound"},
                    "--set medium.resolution=[4096,4096,4096]");
  expectRenderFails(scene, {"--method", "'exact'"}, "--method nonsense");  // exit 2: below
}

TEST_F(Cli, OutputIntoMissingDirectoryOrOntoDirectory) {
  const std::string scene = writeScene(tinyScene());
  RunResult r = run("render " + scene + " -o " + out("no/such/dir/x.exr"));
  EXPECT_NE(r.code, 0);
  EXPECT_NE(r.output.find("does not exist"), std::string::npos) << r.output;
  r = run("render " + scene + " -o " + dir_.string());
  EXPECT_NE(r.code, 0);
  EXPECT_NE(r.output.find("is a directory"), std::string::npos) << r.output;
}

TEST_F(Cli, UnknownBackendIsAUsageError) {
  const std::string scene = writeScene(tinyScene());
  const RunResult r = run("render " + scene + " -o " + out("x.exr") + " --backend tpu");
  EXPECT_NE(r.code, 0);
  EXPECT_FALSE(fs::exists(out("x.exr")));
}

TEST_F(Cli, ExperimentShardAndMergeBadInputs) {
  write("scene.json", tinyScene().dump());
  const std::string cfg = write("exp.json", R"({"scene": "scene.json", "references": ["exact"],
      "methods": ["per-voxel"], "repetitions": 1, "warmup": 0})");
  // Usage errors: exit 2, nothing written.
  for (const char* bad : {"3/2", "0/2", "x", "1/0", "1/2/3"}) {
    const RunResult r = run("experiment " + cfg + " -o " + out("o") + " --shard " + bad);
    EXPECT_EQ(r.code, 2) << bad << ": " << r.output;
    EXPECT_NE(r.output.find("expected K/N with 1 <= K <= N"), std::string::npos) << r.output;
    EXPECT_FALSE(fs::exists(out("o"))) << bad;
  }
  RunResult r = run("experiment -o " + out("o"));
  EXPECT_EQ(r.code, 2) << r.output;
  EXPECT_EQ(r.output.rfind("scatterlab: error: experiment: give CONFIG and -o DIR", 0), 0u)
      << r.output;
  r = run("experiment " + cfg);  // no -o: the same prefix as every other error
  EXPECT_EQ(r.code, 2) << r.output;
  EXPECT_EQ(r.output.rfind("scatterlab: error: experiment: give CONFIG and -o DIR", 0), 0u)
      << r.output;
  r = run("experiment merge " + out("s1") + " -o " + out("m") + " --shard 1/2");
  EXPECT_EQ(r.code, 2) << r.output;
  // Bad input: exit 1, one message naming it, no merged output.
  r = run("experiment merge " + out("nowhere") + " -o " + out("m"));
  EXPECT_EQ(r.code, 1) << r.output;
  EXPECT_NE(r.output.find("nowhere' is not a directory"), std::string::npos) << r.output;
  r = run("experiment " + cfg + " -o " + out("s1") + " --shard 1/2 -q --no-plots");
  ASSERT_EQ(r.code, 0) << r.output;
  r = run("experiment merge " + out("s1") + " -o " + out("m"));
  EXPECT_EQ(r.code, 1) << r.output;
  EXPECT_NE(r.output.find("shard(s) 2 of 2 missing"), std::string::npos) << r.output;
  EXPECT_FALSE(fs::exists(out("m")));
  // --list: the run ids, of one shard with --shard; a bad config is named, exit 1.
  r = run("experiment " + cfg + " --list");
  EXPECT_EQ(r.code, 0) << r.output;
  EXPECT_EQ(r.output, "per-voxel\n");
  r = run("experiment " + cfg + " --list --shard 2/2");
  EXPECT_EQ(r.code, 0) << r.output;
  EXPECT_EQ(r.output, "");
  r = run("experiment " +
          write("bad.json", R"({"scene": "scene.json", "methods": ["per-voxel"], "bogus": 1})") +
          " --list");
  EXPECT_EQ(r.code, 1) << r.output;
  EXPECT_NE(r.output.find("bogus"), std::string::npos) << r.output;
  // Issue 37: overrides and sweep axes are checked before anything runs (they were accepted by
  // --list, and every run failed): a --set is a usage error (2), a config's a config error (1).
  for (const char* bad : {"=", "=1", ".x=1", "camera..width=8", "camera.=8"}) {
    r = run("experiment " + cfg + " --list --set '" + bad + "'");
    EXPECT_EQ(r.code, 2) << bad << ": " << r.output;
    EXPECT_NE(r.output.find("scatterlab: error: --set '"), std::string::npos) << r.output;
    r = run("render " + write("s.json", tinyScene().dump()) + " -o " + out("x.exr") + " --set '" +
            bad + "'");
    EXPECT_EQ(r.code, 2) << bad << ": " << r.output;
    EXPECT_FALSE(fs::exists(out("x.exr")));
  }
  for (const char* axis : {".", "render.", ".render"}) {
    r = run("experiment " +
            write("axis.json", Json{{"scene", "scene.json"},
                                    {"methods", {"per-voxel"}},
                                    {"sweeps", {{{"name", "a"}, {"axes", {{axis, {1, 2}}}}}}}}
                                   .dump()) +
            " --list");
    EXPECT_EQ(r.code, 1) << axis << ": " << r.output;
    EXPECT_NE(r.output.find("is not a dotted scene key"), std::string::npos) << r.output;
  }
  // Shard 2 of 2 has no run (one run, one reference group): its manifest still completes the set.
  r = run("experiment " + cfg + " -o " + out("s2") + " --shard 2/2 -q --no-plots");
  ASSERT_EQ(r.code, 0) << r.output;
  r = run("experiment merge " + out("s1") + " " + out("s2") + " -o " + out("m") + " -q --no-plots");
  EXPECT_EQ(r.code, 0) << r.output;
  EXPECT_TRUE(fs::exists(out("m") + "/results.json"));
}

// --- Issue 17: inputs that crashed, exited with CLI11's codes or left partial files. ---

TEST_F(Cli, UsageErrorsExit2WithThePrefix) {
  const std::string scene = writeScene(tinyScene());
  for (const std::string& args :
       {"render " + scene + " -o " + out("o.exr") + " --bogus",            // CLI11 code 109
        std::string("render"),                                             // 106: required missing
        "render " + scene + " -o " + out("o.exr") + " --backend nope"}) {  // 105: validation
    const RunResult r = run(args);
    EXPECT_EQ(r.code, 2) << args << "\n" << r.output;
    EXPECT_EQ(r.output.rfind("scatterlab: error: ", 0), 0u) << r.output;
  }
  EXPECT_FALSE(fs::exists(out("o.exr")));
}

TEST_F(Cli, DuplicateOutputPathsAreAUsageError) {
  const std::string scene = writeScene(tinyScene());
  // (-o o.exr --png ./o.exr is refused before this check: --png must end in .png.)
  RunResult r =
      run("render " + scene + " -o " + out("o.png") + " --png " + dir_.string() + "/./o.png");
  EXPECT_EQ(r.code, 2) << r.output;
  EXPECT_NE(r.output.find("--output and --png name the same file"), std::string::npos) << r.output;
  EXPECT_FALSE(fs::exists(out("o.png")));
  r = run("render " + scene + " -o " + out("o.exr") + " --stats " + scene);
  EXPECT_EQ(r.code, 2) << r.output;
  EXPECT_NE(r.output.find("scene and --stats"), std::string::npos) << r.output;
}

TEST_F(Cli, ExtremeValuesFailWithTheKeyNotASegfault) {
  // Each crashed with exit 139 or rendered inf/NaN with exit 0 before.
  const std::string scene = writeScene(tinyScene());
  expectRenderFails(scene, {"'camera.position'", "beyond single precision"},
                    "--set camera.position=[0.5,0.5,-1e39]");
  expectRenderFails(scene, {"'camera.up'"}, "--set camera.up=[0,1e300,0]");
  expectRenderFails(scene, {"'background'"}, "--set background=1e39");
  expectRenderFails(scene, {"'camera.position'", "box diagonals"},
                    "--set camera.position=[1e20,0.5,-2]");
  expectRenderFails(write("big.json", "{\"medium\": {\"sigma_t\": 1e400}}"),
                    {"big.json", "number overflow"});
  expectRenderFails(write("deep.json", std::string(100000, '[') + std::string(100000, ']')),
                    {"deep.json", "nesting deeper than 64"});
  expectRenderFails(write("dup.json", "{\"camera\": {}, \"camera\": {}}"),
                    {"dup.json", "duplicate key \"camera\""});
}

TEST_F(Cli, WorkBoundsNameTheStepBeforeRendering) {
  // march_step = 2e-6 of a unit box: 866 026 steps per ray, 6.65e10 for 320x240; it ran
  // practically forever. The same for light marches of `exact` (delta1).
  const std::string scene = writeScene(tinyScene());
  const std::string big = "--set camera.width=320 --set camera.height=240 ";
  expectRenderFails(scene,
                    {"'render.march_step': a step of 2e-06 gives 8.66e+05 steps per view ray",
                     "6.65e+10 steps for 320x240 pixels x 1 spp, above the bound of 1e+10"},
                    big + "--set render.march_step=2e-6");
  expectRenderFails(scene, {"'render.delta1': a step of 2e-06", "above the bound of 1e+12"},
                    big + "--set render.delta1=2e-6");
  // The samples' evaluation: 1e6 samples x 7 traced points (S, 6 for ∇S) x 866 026 steps.
  expectRenderFails(
      scene,
      {"'render.sampler.count', 'render.delta1': evaluating 1000000 samples",
       "6.06e+12 steps in all, above the bound of 1e+12"},
      "--method gradient --set render.delta1=2e-6 --set render.sampler.count=1000000");
}

TEST_F(Cli, MemoryLimitIsCheckedOnTheSumOfTheAllocations) {
  // per-voxel at 128^3: density 8 MiB, radiance 24 MiB, fused volume 32 MiB, each below 48 MiB.
  const std::string scene = writeScene(tinyScene());
  expectRenderFails(scene,
                    {"scatterlab: error: the render's planned allocations need about 64 MiB in "
                     "all, above the memory limit of 48 MiB; the largest: 'render.fast_march'"},
                    "--memory-limit 48M --method per-voxel --set medium.resolution=128");
}

TEST_F(Cli, MemoryLimitFlagAndEnvironment) {
  const std::string scene = writeScene(tinyScene());
  expectRenderFails(scene,
                    {"'medium.resolution': the density volume of 512x512x512 voxels needs about "
                     "512 MiB, above the memory limit of 64 MiB"},
                    "--memory-limit 64M --set medium.resolution=512");
  setenv("SCATTERLAB_MEMORY_LIMIT", "32M", 1);
  expectRenderFails(scene, {"the memory limit of 32 MiB"}, "--set medium.resolution=256");
  setenv("SCATTERLAB_MEMORY_LIMIT", "lots", 1);
  expectRenderFails(scene, {"SCATTERLAB_MEMORY_LIMIT: 'lots' is not a size"});
  unsetenv("SCATTERLAB_MEMORY_LIMIT");
  for (const char* bad : {"12Q", "0", "200%"}) {
    const RunResult r = run("render " + scene + " -o " + out("o.exr") + " --memory-limit " + bad);
    EXPECT_EQ(r.code, 2) << r.output;
    EXPECT_EQ(r.output.rfind("scatterlab: error: --memory-limit", 0), 0u) << r.output;
  }
}

TEST_F(Cli, ThreadsBoundsTheWorkerPool) {
  const std::string scene = writeScene(tinyScene());
  RunResult r = run("--threads 1 render " + scene + " -o " + out("a.exr"));
  EXPECT_EQ(r.code, 0) << r.output;
  r = run("render " + scene + " -o " + out("b.exr") + " --threads 2");
  EXPECT_EQ(r.code, 0) << r.output;
  r = run("compare " + out("a.exr") + " " + out("b.exr"));
  EXPECT_EQ(r.code, 0) << r.output;  // same image whatever the thread count
  EXPECT_NE(r.output.find("max abs error:     0\n"), std::string::npos) << r.output;
  for (const char* bad : {"0", "-3", "many"}) {
    r = run("render " + scene + " -o " + out("c.exr") + " --threads " + bad);
    EXPECT_EQ(r.code, 2) << bad << r.output;
    EXPECT_EQ(r.output.rfind("scatterlab: error: --threads", 0), 0u) << r.output;
  }
}

namespace {

/// Runs the tool with `args` under a file-size limit of `kib` KiB (bash's `ulimit -f`), which
/// fails write(2) with EFBIG as a full disk fails it with ENOSPC; SIGXFSZ is ignored so that the
/// write fails instead of killing the process. Returns the exit status and the output.
std::pair<int, std::string> runWithFileSizeLimit(int kib, const std::string& args) {
  const std::string cmd = "bash -c \"trap '' XFSZ; ulimit -f " + std::to_string(kib) + "; exec " +
                          std::string(SCATTERLAB_CLI) + " " + args + "\" 2>&1";
  FILE* p = popen(cmd.c_str(), "r");
  std::string output;
  std::array<char, 4096> buf;
  while (size_t n = fread(buf.data(), 1, buf.size(), p)) output.append(buf.data(), n);
  return {pclose(p), output};
}

}  // namespace

TEST_F(Cli, FullDiskDuringVdbExportExits1AndLeavesNothing) {
  // The density volume (64^3 floats) exceeds the limit of 64 KiB; the EXR and stats would fit.
  Json doc = tinyScene();
  doc["medium"]["resolution"] = 64;
  doc["render"]["method"] = "per-voxel";
  const std::string scene = writeScene(doc);
  const auto [status, output] =
      runWithFileSizeLimit(64, "render " + scene + " -q -o " + out("o.exr") + " --stats " +
                                   out("s.json") + " --density-vdb " + out("d.vdb"));
  ASSERT_TRUE(WIFEXITED(status)) << output;
  EXPECT_EQ(WEXITSTATUS(status), 1) << output;
  EXPECT_NE(output.find("cannot write '" + out("d.vdb") + "'"), std::string::npos) << output;
  for (const auto& e : fs::directory_iterator(dir_))
    EXPECT_EQ(e.path().filename().string(), "scene.json") << "left behind: " << e.path();
}

// Issue 37: the EXR writer's message on a full disk was OpenEXR's "Cannot determine current
// file position"; it names the write's failure now (EFBIG here, ENOSPC on a full disk), and
// nothing is left behind.
TEST_F(Cli, FullDiskDuringExrWriteNamesTheWriteFailure) {
  Json doc = tinyScene();
  doc["camera"]["width"] = 160;
  doc["camera"]["height"] = 120;
  const std::string scene = writeScene(doc);
  const auto [status, output] =
      runWithFileSizeLimit(8, "render " + scene + " -q -o " + out("o.exr") + " --method per-voxel");
  ASSERT_TRUE(WIFEXITED(status)) << output;
  EXPECT_EQ(WEXITSTATUS(status), 1) << output;
  // Where the limit is hit decides the wording: inside OpenEXR ("cannot write EXR '...': ...
  // write failed: File too large") or at the final flush ("cannot write '...': File too large").
  EXPECT_NE(output.find("cannot write"), std::string::npos) << output;
  EXPECT_NE(output.find(out("o.exr") + "'"), std::string::npos) << output;
  EXPECT_NE(output.find("File too large"), std::string::npos) << output;
  EXPECT_EQ(output.find("Cannot determine"), std::string::npos) << output;
  for (const auto& e : fs::directory_iterator(dir_))
    EXPECT_EQ(e.path().filename().string(), "scene.json") << "left behind: " << e.path();
}

TEST_F(Cli, InfoCountsNonFinitePixelsInsteadOfPrintingNanMeans) {
  scatterlab::Image img(2, 1);
  img.pixels()[0] = scatterlab::Vec3(1.0f, 2.0f, 3.0f);
  img.pixels()[1] = scatterlab::Vec3(std::nanf(""), INFINITY, 5.0f);
  scatterlab::writeExr(img, out("nan.exr"));
  const RunResult r = run("info " + out("nan.exr"));
  EXPECT_EQ(r.code, 0) << r.output;
  EXPECT_NE(r.output.find("mean [1 2 4]"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("1 NaN and 1 inf"), std::string::npos) << r.output;
  EXPECT_EQ(r.output.find("nan ]"), std::string::npos) << r.output;
}

// Issue 25: the tool's own arguments are blamed as such (exit 2, the flag named, the likely
// spelling suggested), before the scene is read and with nothing written.
TEST_F(Cli, BadArgumentsAreUsageErrorsNamingTheFlag) {
  const std::string scene = writeScene(tinyScene());
  const auto usage = [&](const std::string& extra, std::initializer_list<std::string> fragments) {
    const RunResult r = run("render " + scene + " -o " + out("o.exr") + " " + extra);
    EXPECT_EQ(r.code, 2) << extra << ": " << r.output;
    EXPECT_EQ(r.output.rfind("scatterlab: error: ", 0), 0u) << r.output;
    for (const auto& f : fragments)
      EXPECT_NE(r.output.find(f), std::string::npos) << "'" << r.output << "' lacks '" << f << "'";
    EXPECT_FALSE(fs::exists(out("o.exr"))) << extra;
    return r.output;
  };
  std::string o = usage("--method per-voxle",
                        {"--method: unknown method 'per-voxle' (did you mean 'per-voxel'?)",
                         "allowed: 'adaptive', 'exact', "});
  EXPECT_EQ(o.find(scene), std::string::npos) << "blames the scene file: " << o;
  usage("--method nonsense", {"--method: unknown method 'nonsense'; allowed: "});
  usage("--set camera.width", {"--set 'camera.width': expected KEY=VALUE", "camera.width=640"});
  // --fps: a clear range, not CLI11's upper bound DBL_MAX in 309 digits.
  for (const std::string fps : {"-3", "0", "nan", "inf", "x"}) {
    o = usage("--frames 0:1 --fps " + fps,
              {"--fps", "'" + fps + "' is not a frame rate in (0, 1e9]"});
    EXPECT_LT(o.size(), 200u) << o;
  }
  usage("--png " + out("o.exr2"), {"--png", "does not end in .png"});
  usage("--png " + out("o.exr"), {"does not end in .png"});
  usage("--metod exact", {"(did you mean '--method'?)"});
  usage("--backend GPU", {"--backend"});
  // Outside the render command: a misspelt command.
  const RunResult r = run("rendr " + scene);
  EXPECT_EQ(r.code, 2) << r.output;
  EXPECT_NE(r.output.find("'rendr' is not a command (did you mean 'render'?)"), std::string::npos)
      << r.output;
}

// Issue 25: `scatterlab render smoke.vdb` says what the file is and what to do, not where the
// JSON parser stopped.
TEST_F(Cli, RenderingATruncatedVolumeFileNamesIt) {
  // A volume file is a quick look (tests/apps/test_quick_look.cpp); this one ends after its
  // magic number and version.
  const std::string vdb = out("smoke.vdb");
  std::ofstream(vdb, std::ios::binary) << std::string("\x20\x42\x44\x56\0\0\0\0\xdc\0\0\0", 12);
  const RunResult r = run("render " + vdb + " -o " + out("o.exr"));
  EXPECT_EQ(r.code, 1) << r.output;
  EXPECT_NE(r.output.find("scatterlab: error: '" + vdb + "' is not a valid VDB file"),
            std::string::npos)
      << r.output;
  EXPECT_EQ(r.output.find("malformed JSON"), std::string::npos) << r.output;
  EXPECT_FALSE(fs::exists(out("o.exr")));
}

// Issue 25: the methods are discoverable without provoking an error.
TEST_F(Cli, InfoListsTheMethods) {
  RunResult r = run("info --methods");
  ASSERT_EQ(r.code, 0) << r.output;
  for (const std::string m : {"adaptive ", "exact ", "gradient ", "per-voxel "})
    EXPECT_NE(("\n" + r.output).find("\n" + m), std::string::npos) << m << ": " << r.output;
  EXPECT_EQ(r.output.rfind("adaptive ", 0), 0u) << r.output;  // sorted by name
  r = run("info --methods --json");
  ASSERT_EQ(r.code, 0) << r.output;
  const Json j = Json::parse(r.output);
  EXPECT_EQ(j["exact"]["backends"][0], "cpu");
  EXPECT_FALSE(j["per-voxel"]["summary"].get<std::string>().empty());
  scatterlab::initialize();
  EXPECT_EQ(j.size(), scatterlab::methods().names().size());
}

// `info --keys` prints the render keys from the code's tables (the rows docs/scene-format.md is
// checked against): each key once per distinct row, with the methods that read it.
TEST_F(Cli, InfoListsTheRenderKeys) {
  RunResult r = run("info --keys");
  ASSERT_EQ(r.code, 0) << r.output;
  EXPECT_NE(r.output.find("render.probes (int; default 40 with up to 4 lights"), std::string::npos)
      << r.output;
  EXPECT_NE(r.output.find("render.slicing (string; default ray-steps; allowed ray-steps, "
                          "view-planes) [gpu-raster only]"),
            std::string::npos)
      << r.output;
  r = run("info --keys --json");
  ASSERT_EQ(r.code, 0) << r.output;
  const Json j = Json::parse(r.output);
  EXPECT_EQ(j["probes"].size(), 1u);
  EXPECT_EQ(j["probes"][0]["methods"], Json::array({"adaptive"}));
  EXPECT_EQ(j["probes"][0]["type"], "int");
  ASSERT_EQ(j["steps"].size(), 2u);  // jittered-march's and light-space-march's
  scatterlab::initialize();          // every method reads delta1
  EXPECT_EQ(j["delta1"][0]["methods"].size(), scatterlab::methods().names().size())
      << j["delta1"].dump();
}

// Every experiment config the repository ships is checked by the tool as it would run it
// (`experiment CONFIG --list`: keys, scenes, methods, sweeps, baselines; nothing rendered), so
// a config that names a method, a key or a scene file that is gone fails here, not hours into
// a run. Each lists at least one run.
TEST_F(Cli, EveryShippedExperimentConfigIsValid) {
  int configs = 0;
  for (const auto& e : std::filesystem::directory_iterator(std::string(SCATTERLAB_SOURCE_DIR) +
                                                           "/data/experiments")) {
    if (e.path().extension() != ".json") continue;
    const RunResult r = run("experiment " + e.path().string() + " --list");
    EXPECT_EQ(r.code, 0) << e.path() << ": " << r.output;
    EXPECT_FALSE(r.output.empty()) << e.path();  // one run id a line
    ++configs;
  }
  EXPECT_GE(configs, 12);
}

// Issue 25: the shipped fig3 config runs without a terminal warning (its scene's render.sampler
// is ignored by the references by design; log.txt notes it).
TEST_F(Cli, ShippedFig3ConfigPrintsNoWarning) {
  const std::string cfg = std::string(SCATTERLAB_SOURCE_DIR) + "/data/experiments/fig3.json";
  const RunResult r = run("experiment " + cfg + " -o " + out("fig3") +
                          " --set camera.width=24 --set camera.height=18 --set "
                          "medium.resolution=16 --no-plots -q");
  ASSERT_EQ(r.code, 0) << r.output;
  EXPECT_EQ(r.output.find("warning"), std::string::npos) << r.output;
  std::ifstream log(out("fig3/log.txt"));
  const std::string text((std::istreambuf_iterator<char>(log)), {});
  EXPECT_NE(text.find("reference exact ignores render.sampler"), std::string::npos) << text;
}
