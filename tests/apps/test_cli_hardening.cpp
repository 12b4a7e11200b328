/// Issue 26 ("hardening, round two") through the `scatterlab` tool: far geometry is an error,
/// not Embree's abort; no image with a non-finite pixel is written; `compare` refuses non-finite
/// pixels; one file under two spellings; special files written through; an OBJ's .mtl checked
/// like every other file.

#include <gtest/gtest.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <thread>

#include "api/scatterlab.h"
#include "core/sanitizers.h"
#include "support/cli.h"
#include "support/scenes.h"

namespace fs = std::filesystem;
using scatterlab::Json;

namespace {

using scatterlab::testing::RunResult;

// kAddressSanitizer (core/sanitizers.h): this test and the tool it runs are one build tree
// with one set of flags; under ASan the tool aborts before main under any `ulimit -v`
// ("ReserveShadowMemoryRange failed", exit 134).
using scatterlab::kAddressSanitizer;

/// `scatterlab ARGS` under `timeout` and a 2 GiB address-space limit, so that a regression
/// (a FIFO read forever, /dev/zero read into memory) fails the test instead of hanging it. Under
/// AddressSanitizer only the timeout applies (see kAddressSanitizer); ASan's own allocator
/// limits still turn a runaway allocation into a failure.
RunResult runLimited(const std::string& args, int seconds = 120, long addressSpaceKiB = 2097152) {
  const std::string limit =
      kAddressSanitizer ? "" : "ulimit -v " + std::to_string(addressSpaceKiB) + "; ";
  return scatterlab::testing::run(args, limit + "timeout -s KILL " + std::to_string(seconds) + " ");
}

const std::string kSource = SCATTERLAB_SOURCE_DIR;
const std::string kSmall = " --set camera.width=24 --set camera.height=18 ";

class Hardening : public scatterlab::testing::TempDirTest {
 protected:
  Hardening() : TempDirTest("scatterlab_hardening2") {}

  static Json tinyScene() {
    return Json::parse(R"({
      "medium": {"bounds": {"min": [0,0,0], "max": [1,1,1]},
                 "density": {"type": "gaussians", "blobs": [{"center": [0.5,0.5,0.5], "radius": 0.25}]},
                 "resolution": 16, "sigma_t": 4.0, "albedo": 0.6},
      "lights": [{"type": "point", "position": [0.5,1.4,0.5], "intensity": [4,4,4]}],
      "objects": [{"type": "sphere", "center": [0.5,0.15,0.5], "radius": 0.1}],
      "camera": {"position": [0.5,0.5,-2], "look_at": [0.5,0.5,0.5], "width": 16, "height": 12}})");
  }
  std::string scene(const Json& j, const std::string& name = "scene.json") const {
    return write(name, j.dump(2));
  }

  /// A render expected to fail: exit 1 (or `code`), every fragment in the message, one
  /// `scatterlab: error:` line, and no output file.
  void expectFails(const std::string& args, std::initializer_list<std::string> fragments,
                   int code = 1) {
    const std::string exr = out("o.exr");
    const RunResult r = runLimited("render " + args + " -q -o " + exr);
    EXPECT_EQ(r.code, code) << r.output;
    EXPECT_NE(r.output.find("scatterlab: error:"), std::string::npos) << r.output;
    for (const auto& f : fragments)
      EXPECT_NE(r.output.find(f), std::string::npos) << "'" << r.output << "' lacks '" << f << "'";
    EXPECT_FALSE(fs::exists(exr));
  }
};

using FarGeometry = Hardening;
using FiniteImages = Hardening;
using CompareNonFinite = Hardening;
using OutputPaths = Hardening;
using SpecialFiles = Hardening;
using ObjMaterialLib = Hardening;
using Messages = Hardening;

}  // namespace

// 1. Each aborted in Embree's `ray.valid()` assertion (exit 134, no error line) before.
TEST_F(FarGeometry, ObjectsBeyondTheCoordinateBoundAreRefusedNotAnAbort) {
  expectFails(
      kSource + "/data/scenes/window.json" + kSmall + "--set 'objects.10.max=[0.9,0.35,1e20]'",
      {"'objects[10].max'", "beyond +-1e+15", "allowed: every coordinate within +-1e+15"});
  Json j = tinyScene();
  j["objects"][0]["center"] = {0.5, 0.15, 2e15};
  expectFails(scene(j), {"'objects[0].center'", "beyond +-1e+15"});
  j = tinyScene();
  j["objects"][0]["radius"] = 1e16;
  expectFails(scene(j), {"'objects[0].radius'", "beyond +-1e+15"});
  // An OBJ vertex at 1e38 (finite in float) and a far translate of a good mesh.
  write("far.obj", "v 0 0 0\nv 1 0 0\nv 0 1e38 0\nf 1 2 3\n");
  write("near.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n");
  j = tinyScene();
  j["objects"] = Json::array({{{"type", "mesh"}, {"file", "far.obj"}}});
  expectFails(scene(j), {"objects[0].file", "vertex 3 of", "beyond +-1e+15"});
  j["objects"] = Json::array(
      {{{"type", "mesh"}, {"file", "near.obj"}, {"transform", {{"translate", {0, 0, 1e20}}}}}});
  expectFails(scene(j), {"objects[0].file", "vertex 1 of", "after the transform"});
  // The bound is inclusive of ordinary far scenes: a box 1e14 away renders.
  j = tinyScene();
  j["objects"] = Json::array({{{"type", "box"}, {"min", {0, 0, 1e14}}, {"max", {1, 1, 2e14}}}});
  const RunResult ok = runLimited("render " + scene(j) + " -q -o " + out("ok.exr"));
  EXPECT_EQ(ok.code, 0) << ok.output;
}

TEST_F(FarGeometry, GaussianCentresUsedAsSamplePointsAreBounded) {
  Json j = tinyScene();
  j["medium"]["density"]["blobs"].push_back({{"center", {0.5, 0.5, 1e20}}, {"radius", 0.25}});
  j["render"] = {{"method", "rbf"}, {"sampler", {{"type", "gaussian-centres"}}}};
  expectFails(scene(j), {"'medium.density.blobs[1].center'", "beyond the coordinate bound",
                         "within +-1e+15"});
  // A blob that drifts there with its velocity.
  j["medium"]["density"]["blobs"][1] = {
      {"center", {0.5, 0.5, 2}}, {"radius", 0.25}, {"velocity", {0, 0, 1e20}}};
  j["medium"]["density"]["time"] = 1;
  expectFails(scene(j), {"'medium.density.blobs[1].velocity'", "at time 1"});
  // Lights and the camera: a box near the bound has diagonals of 3.5e15, and 1e6 of them
  // allowed a camera at 1e20.
  j = tinyScene();
  j["medium"]["bounds"] = {{"min", {-1e15, -1e15, -1e15}}, {"max", {1e15, 1e15, 1e15}}};
  j["camera"]["position"] = {0, 0, -1e20};
  j["camera"]["look_at"] = {0, 0, 0};
  expectFails(scene(j), {"'camera.position'", "beyond the coordinate bound"});
}

// 2. Each wrote an image with inf or NaN pixels with exit 0 before.
TEST_F(FiniteImages, HugeButFiniteValuesAreRefusedWithTheirKey) {
  const std::string glow = scatterlab::testing::kGlow + kSmall;
  for (const char* method : {"exact", "radial-blur", "per-voxel"})
    expectFails(glow + "--method " + std::string(method) + " --set lights.0.intensity=1e36",
                {"'lights[0].intensity'", "1e+36", "allowed: [0, 1e+20]"});
  expectFails(glow + "--method radial-blur --set render.weight=3.4e38",
              {"'render.weight'", "allowed: [0, 1e+06]"});
  expectFails(glow + "--method radial-blur --set render.exposure=3.4e38",
              {"'render.exposure'", "allowed: [0, 1e+06]"});
  Json j = tinyScene();
  j["medium"]["density"] = {{"type", "grid"}, {"dims", {2, 1, 1}}, {"values", {1.0, 1e300}}};
  expectFails(scene(j), {"'medium.density.values'", "element 1", "[0, 3.40282e+38]"});
}

TEST_F(FiniteImages, AnOverflowThatEveryBoundAllowsIsAnErrorNotAnImage) {
  // Two blobs of weight 3e38 at one centre: each weight is within float range, their sum is
  // inf, and these four methods made NaN pixels of it (108, 180, 75 and 48 channel values at
  // 16x12), written with exit 0; the others happen to stay finite (transmittance 0).
  Json j = tinyScene();
  j["medium"]["density"]["blobs"] = {
      {{"center", {0.5, 0.5, 0.5}}, {"radius", 0.2}, {"weight", 3e38}},
      {{"center", {0.5, 0.5, 0.5}}, {"radius", 0.2}, {"weight", 3e38}}};
  j.erase("objects");
  const std::string s = scene(j);
  for (const char* method : {"rbf", "nearest", "light-space-march", "froxel"})
    expectFails(s + " --backend cpu --method " + std::string(method) + " --png " + out("o.png"),
                {"method '" + std::string(method) + "' (cpu) produced", " NaN, 0 inf; the first at",
                 "no image was written"});
  EXPECT_FALSE(fs::exists(out("o.png")));
}

// 3. Relative L2 0 and PSNR inf against a NaN reference, exit 0, before.
TEST_F(CompareNonFinite, NonFinitePixelsInEitherImageAreAnError) {
  scatterlab::Image good(4, 3), nan(4, 3), inf(4, 3);
  for (auto* im : {&good, &nan, &inf})
    for (auto& p : im->pixels()) p = scatterlab::Vec3(0.5f);
  nan.at(2, 1) = scatterlab::Vec3(std::nanf(""), 0.5f, 0.5f);
  inf.at(3, 2).y = INFINITY;
  scatterlab::writeExr(good, out("good.exr"));
  scatterlab::writeExr(nan, out("nan.exr"));
  scatterlab::writeExr(inf, out("inf.exr"));
  for (const auto& [a, b, bad, where] :
       {std::tuple{"good.exr", "nan.exr", "nan.exr", "1 NaN, 0 inf; the first at pixel (2, 1)"},
        std::tuple{"nan.exr", "good.exr", "nan.exr", "1 NaN, 0 inf; the first at pixel (2, 1)"},
        std::tuple{"good.exr", "inf.exr", "inf.exr", "0 NaN, 1 inf; the first at pixel (3, 2)"}}) {
    for (const char* json : {"", " --json"}) {
      const RunResult r =
          runLimited("compare " + out(a) + " " + out(b) + json + " --diff " + out("d.png"));
      EXPECT_EQ(r.code, 1) << r.output;
      EXPECT_NE(r.output.find("scatterlab: error: image '" + out(bad) + "' has 1 non-finite"),
                std::string::npos)
          << r.output;
      EXPECT_NE(r.output.find(where), std::string::npos) << r.output;
      EXPECT_EQ(r.output.find("rel"), std::string::npos) << r.output;  // no score printed
      EXPECT_FALSE(fs::exists(out("d.png")));
    }
  }
  // The library call names which of the two.
  try {
    scatterlab::compareImages(good, inf);
    ADD_FAILURE() << "no error";
  } catch (const scatterlab::ConfigError& e) {
    EXPECT_NE(std::string(e.what()).find("the reference has 1 non-finite"), std::string::npos)
        << e.what();
  }
  EXPECT_THROW(scatterlab::compareImages(scatterlab::Image(0, 0), scatterlab::Image(0, 0)),
               scatterlab::ConfigError);
  const RunResult same =
      runLimited("compare " + out("good.exr") + " " + out("good.exr") + " --json");
  ASSERT_EQ(same.code, 0) << same.output;
  EXPECT_EQ(Json::parse(same.output)["rel_l2"], 0.0);
}

// 5. Caught only when the file existed before.
TEST_F(OutputPaths, OneNewFileUnderTwoSpellingsIsAUsageError) {
  const std::string s = scene(tinyScene());
  fs::create_directories(dir_ / "sub");
  fs::create_directory_symlink(dir_ / "sub", dir_ / "link");
  const std::string d = dir_.string();
  const std::vector<std::pair<std::string, std::string>> pairs = {
      {d + "/o.png", d + "/sub/../o.png"},
      {d + "/o.png", d + "/nosuch/../o.png"},
      {d + "/sub/o.png", d + "/link/o.png"},
      {d + "/o.png", d + "/./o.png"},
  };
  for (const auto& [a, b] : pairs) {
    const RunResult r = runLimited("render " + s + " -q -o " + a + " --png " + b);
    EXPECT_EQ(r.code, 2) << a << " " << b << ": " << r.output;
    EXPECT_NE(r.output.find("--output and --png name the same file"), std::string::npos)
        << r.output;
    EXPECT_FALSE(fs::exists(a)) << a;
  }
  // Relative against relative and absolute, from the working directory (the issue's cases).
  const fs::path cwd = fs::current_path();
  fs::current_path(dir_);
  const RunResult dot = runLimited("render " + s + " -q -o o.png --png ./o.png");
  const RunResult abs = runLimited("render " + s + " -q -o o.png --png " + d + "/o.png");
  const RunResult up = runLimited("render " + s + " -q -o o.png --png sub/../o.png");
  fs::current_path(cwd);
  for (const RunResult& r : {dot, abs, up}) {
    EXPECT_EQ(r.code, 2) << r.output;
    EXPECT_NE(r.output.find("--output and --png name the same file"), std::string::npos)
        << r.output;
  }
  EXPECT_FALSE(fs::exists(dir_ / "o.png"));
  // An existing file and a link to it are one file too.
  std::ofstream(dir_ / "stats.json") << "{}";
  fs::create_symlink(dir_ / "stats.json", dir_ / "stats-link.json");
  const RunResult l = runLimited("render " + s + " -q -o " + d + "/x.exr --stats " + d +
                                 "/stats-link.json --samples-png " + d + "/stats.json");
  EXPECT_EQ(l.code, 2) << l.output;
}

// 6. `--stats` at a FIFO, a device or a link to one became a regular file before.
TEST_F(SpecialFiles, StatsAreWrittenThroughDevicesFifosAndLinks) {
  const std::string s = scene(tinyScene());
  // A link to /proc/self/fd/1: the tool's standard output.
  fs::create_symlink("/proc/self/fd/1", dir_ / "stdout.json");
  RunResult r =
      runLimited("render " + s + " -q -o " + out("a.exr") + " --stats " + out("stdout.json"));
  ASSERT_EQ(r.code, 0) << r.output;
  EXPECT_TRUE(fs::is_symlink(dir_ / "stdout.json"));
  const Json stats = Json::parse(r.output);
  EXPECT_EQ(stats["width"], 16);
  // A link to /dev/null.
  fs::create_symlink("/dev/null", dir_ / "null.json");
  r = runLimited("render " + s + " -q -o " + out("b.exr") + " --stats " + out("null.json"));
  ASSERT_EQ(r.code, 0) << r.output;
  EXPECT_TRUE(fs::is_symlink(dir_ / "null.json"));
  EXPECT_TRUE(fs::is_character_file("/dev/null"));
  // A FIFO with a reader.
  const std::string fifo = out("stats.fifo");
  ASSERT_EQ(::mkfifo(fifo.c_str(), 0600), 0);
  std::string got;
  std::thread reader([&] { got = scatterlab::testing::drainFifo(fifo, std::chrono::seconds(60)); });
  r = runLimited("render " + s + " -q -o " + out("c.exr") + " --stats " + fifo, 60);
  reader.join();
  ASSERT_EQ(r.code, 0) << r.output;
  EXPECT_TRUE(fs::is_fifo(fifo));
  ASSERT_TRUE(Json::accept(got)) << got;
  EXPECT_EQ(Json::parse(got)["width"], 16);
  EXPECT_TRUE(fs::exists(out("c.exr")));
  // -o onto a dangling link: refused before rendering, the link left alone.
  fs::create_symlink(dir_ / "gone" / "x.exr", dir_ / "dangling.exr");
  r = runLimited("render " + s + " -q -o " + out("dangling.exr"));
  EXPECT_EQ(r.code, 1) << r.output;
  EXPECT_NE(r.output.find("output '" + out("dangling.exr") + "' is a symbolic link to '" +
                          (dir_ / "gone" / "x.exr").string() + "', which does not exist"),
            std::string::npos)
      << r.output;
  EXPECT_TRUE(fs::is_symlink(dir_ / "dangling.exr"));
}

// 7. `mtllib /dev/zero` grew memory without bound, a FIFO blocked forever, a face index of
// 4294967297 wrapped to 1.
TEST_F(ObjMaterialLib, TheMtlIsCheckedLikeEveryOtherFileAndIndicesAreRangeChecked) {
  const std::string tri = "v 0 0 0\nv 1 0 0\nv 0 1 0\n";
  Json j = tinyScene();
  j["objects"] = Json::array({{{"type", "mesh"}, {"file", "m.obj"}}});
  const std::string s = scene(j);
  write("m.obj", "mtllib /dev/zero\n" + tri + "f 1 2 3\n");
  expectFails(s,
              {"'objects[0].file'", "material library (.mtl) '/dev/zero' is not a regular file"});
  ASSERT_EQ(::mkfifo(out("fifo.mtl").c_str(), 0600), 0);
  write("m.obj", "mtllib fifo.mtl\n" + tri + "f 1 2 3\n");
  expectFails(s, {"fifo.mtl' is not a regular file"});
  write("m.obj", tri + "f 1 2 4294967297\n");
  expectFails(s, {"'objects[0].file': line 4 of", "face index 4294967297 is out of range"});
  write("m.obj", tri + "f 1 2 -99999999999\n");
  expectFails(s, {"face index -99999999999 is out of range"});
  // A regular .mtl beside the OBJ still gives the faces its Kd; a missing one the default.
  write("good.mtl", "newmtl red\nKd 0.9 0.1 0.1\n");
  write("m.obj", "mtllib good.mtl\n" + tri + "usemtl red\nf 1 2 3\n");
  RunResult r = runLimited("render " + s + " -q -o " + out("a.exr"));
  EXPECT_EQ(r.code, 0) << r.output;
  write("m.obj", "mtllib missing.mtl\n" + tri + "f 1 2 3\n");
  r = runLimited("render " + s + " -q -o " + out("b.exr"));
  EXPECT_EQ(r.code, 0) << r.output;
}

// 9, 10, 12: silent wrong input, limits with gaps, "internal error" where a message belongs.
TEST_F(Messages, WrongInputIsNamedNotSilentOrInternal) {
  const std::string s = scene(tinyScene());
  // --exposure nan wrote an all-black PNG with exit 0; --fps nan exited 1 without naming it.
  RunResult r = runLimited("render " + s + " -q -o " + out("a.png") + " --exposure nan");
  EXPECT_EQ(r.code, 2) << r.output;
  EXPECT_NE(r.output.find("--exposure"), std::string::npos) << r.output;
  EXPECT_FALSE(fs::exists(out("a.png")));
  r = runLimited("render " + s + " -q -o " + out("a.exr") + " --frames 0:1 --fps nan");
  EXPECT_EQ(r.code, 2) << r.output;
  EXPECT_NE(r.output.find("--fps"), std::string::npos) << r.output;
  // A moving density's time of the wrong type became 0.
  Json j = tinyScene();
  j["medium"]["density"]["blobs"][0]["velocity"] = {0.1, 0, 0};
  j["medium"]["density"]["time"] = "soon";
  expectFails(scene(j, "moving.json"), {"'medium.density.time': expected a number, got \"soon\""});
  // A value with a line break printed a second, fake `scatterlab: error:` line; a 100 KB value
  // was echoed whole.
  r = runLimited("render " + s + " -q -o " + out("b.exr") +
                 " --method \"$(printf 'nonsense\\nscatterlab: error: fake')\"");
  EXPECT_EQ(r.code, 2) << r.output;  // an unknown --method is a usage error (issue 25)
  EXPECT_EQ(r.output.rfind("scatterlab: error:", 0), 0u) << r.output;
  EXPECT_EQ(r.output.find("\nscatterlab: error:"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("nonsense\n  scatterlab: error: fake"), std::string::npos) << r.output;
  r = runLimited("render " + s + " -q -o " + out("b.exr") + " --method " +
                 std::string(100000, 'm'));
  EXPECT_EQ(r.code, 2);
  EXPECT_LT(r.output.size(), 2500u);
  EXPECT_NE(r.output.find("characters left out"), std::string::npos) << r.output.substr(0, 300);
  // A loop of links was "does not exist".
  fs::create_symlink(dir_ / "loop2.json", dir_ / "loop1.json");
  fs::create_symlink(dir_ / "loop1.json", dir_ / "loop2.json");
  r = runLimited("render " + out("loop1.json") + " -q -o " + out("c.exr"));
  EXPECT_EQ(r.code, 1) << r.output;
  EXPECT_NE(r.output.find("is a loop of symbolic links"), std::string::npos) << r.output;
  // An output name of 250 bytes (valid) failed with "File name too long" for its temporary.
  const std::string longName = out(std::string(246, 'n') + ".exr");
  r = runLimited("render " + s + " -q -o " + longName);
  EXPECT_EQ(r.code, 0) << r.output;
  EXPECT_TRUE(fs::exists(longName));
  // experiment -o onto an existing file: "internal error: filesystem error: ..." before.
  write("exp.json", Json{{"scene", "scene.json"}, {"methods", {"exact"}}}.dump());
  std::ofstream(out("file")) << "x";
  r = runLimited("experiment " + out("exp.json") + " -o " + out("file"));
  EXPECT_EQ(r.code, 1) << r.output;
  EXPECT_EQ(r.output.find("internal error"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("output directory '" + out("file") + "' exists and is not a directory"),
            std::string::npos)
      << r.output;
}

TEST_F(Messages, TheDefaultMemoryLimitFollowsAnAddressSpaceLimit) {
  if (kAddressSanitizer) GTEST_SKIP() << "AddressSanitizer cannot start under ulimit -v";
  // Under ulimit -v 1.5 GiB, per-voxel at 320^3 (about 1.1 GiB planned) ran 11 s and died with
  // "internal error: std::bad_alloc": the default limit was 75 % of physical memory.
  const RunResult r = runLimited("render " + scene(tinyScene()) + " -q -o " + out("a.exr") +
                                     " --method per-voxel --set medium.resolution=320",
                                 120, 1536 * 1024);
  EXPECT_EQ(r.code, 1) << r.output;
  EXPECT_NE(r.output.find("above the memory limit"), std::string::npos) << r.output;
  EXPECT_EQ(r.output.find("internal error"), std::string::npos) << r.output;
  EXPECT_FALSE(fs::exists(out("a.exr")));
}

// 10. No memory or work bound for the per-pixel competitors: a 1024x1024x16 froxel grid peaked
// at 364 MB under --memory-limit 64M, 4096^2 shadow maps x 4 lights at 1.68 GB under 128M, and
// renders of hours were accepted.
TEST_F(Messages, TheCompetitorsHaveMemoryAndWorkBounds) {
  Json j = tinyScene();
  j["lights"] = Json::array();
  for (int i = 0; i < 4; ++i)
    j["lights"].push_back(
        {{"type", "point"}, {"position", {0.2 + 0.2 * i, 1.4, 0.5}}, {"intensity", 1.0}});
  const std::string s = scene(j);
  const std::string big = " --set camera.width=320 --set camera.height=240 --backend cpu ";
  expectFails("--memory-limit 64M " + s + " --backend cpu --method froxel" +
                  " --set 'render.froxel_grid=[1024,1024,16]'",
              {"'render.froxel_grid': the froxel volume of 1024x1024x16 froxels, 256 MiB",
               "above the memory limit of 64 MiB"});
  expectFails("--memory-limit 128M " + s + " --backend cpu --method light-space-march" +
                  " --set render.shadow_map.resolution=4096",
              {"'render.shadow_map.resolution': the shadow maps (24 layers of 4.1e+03^2 texels)",
               "above the memory limit of 128 MiB"});
  expectFails(s + big + "--method jittered-march --set render.delta1=2e-6",
              {"'render.delta1'", "light-march steps", "above the bound of 1e+12"});
  expectFails(s + big + "--method froxel --set render.delta1=2e-6",
              {"'render.delta1'", "froxels", "above the bound of 1e+12"});
  expectFails(s + big + "--method light-space-march --set render.steps=65536" +
                  " --set render.interleave=1 --set camera.width=1024 --set camera.height=1024",
              {"'render.steps'", "view-ray terms, above the bound of 1e+10"});
}
