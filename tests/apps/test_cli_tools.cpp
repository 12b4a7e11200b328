/// Issue 36's rough list, through the tool: `convert` (EXR -> PNG with render's transform),
/// `compare` given a PNG, `compare --diff-signed` (the gallery's signed error map) and
/// `render -r WxH`. Good runs write what they say; bad input gives one clear message, its exit
/// code, and no output file.

#include <gtest/gtest.h>
#include <png.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <tuple>

#include "api/scatterlab.h"
#include "support/cli.h"

namespace fs = std::filesystem;
using scatterlab::Image;
using scatterlab::Json;
using scatterlab::Vec3;

namespace {

using scatterlab::testing::run;
using scatterlab::testing::RunResult;

/// An 8-bit RGB PNG read back: width, height and the bytes, row-major, 3 a pixel.
struct Png {
  int width = 0, height = 0;
  std::vector<unsigned char> rgb;
  std::array<int, 3> at(int x, int y) const {
    const std::size_t i = 3 * (std::size_t(y) * std::size_t(width) + std::size_t(x));
    return {rgb[i], rgb[i + 1], rgb[i + 2]};
  }
};

Png readPng(const std::string& path) {
  png_image pi;
  std::memset(&pi, 0, sizeof pi);
  pi.version = PNG_IMAGE_VERSION;
  Png out;
  if (!png_image_begin_read_from_file(&pi, path.c_str())) {
    ADD_FAILURE() << "cannot read PNG '" << path << "': " << pi.message;
    return out;
  }
  pi.format = PNG_FORMAT_RGB;
  out.width = int(pi.width);
  out.height = int(pi.height);
  out.rgb.resize(PNG_IMAGE_SIZE(pi));
  if (!png_image_finish_read(&pi, nullptr, out.rgb.data(), 0, nullptr))
    ADD_FAILURE() << "cannot decode PNG '" << path << "': " << pi.message;
  return out;
}

class CliTools : public scatterlab::testing::TempDirTest {
 protected:
  CliTools() : TempDirTest("scatterlab_tools") {}

  static Json tinyScene() { return Json::parse(scatterlab::testing::kTinySceneJson); }
  std::string writeScene() const { return write("scene.json", tinyScene().dump(2)); }

  /// Runs `args`, expecting exit `code`, each of `fragments` in the output, one line of output
  /// (two for usage errors: CLI11's "Run with --help" follows), and `unwritten` not created.
  void expectFails(const std::string& args, int code, std::initializer_list<std::string> fragments,
                   const std::string& unwritten) {
    const RunResult r = run(args);
    EXPECT_EQ(r.code, code) << args << ": " << r.output;
    EXPECT_EQ(r.output.rfind("scatterlab: error: ", 0), 0u) << args << ": " << r.output;
    EXPECT_EQ(std::count(r.output.begin(), r.output.end(), '\n'), code == 2 ? 2 : 1)
        << args << ": " << r.output;
    for (const auto& f : fragments)
      EXPECT_NE(r.output.find(f), std::string::npos)
          << args << ": '" << r.output << "' lacks '" << f << "'";
    EXPECT_FALSE(fs::exists(unwritten)) << args;
    for (const auto& e : fs::directory_iterator(dir_))
      EXPECT_EQ(e.path().filename().string().find(".tmp"), std::string::npos) << e.path();
  }
};

}  // namespace

// `convert` applies render's PNG transform (writePng: 2^exposure, the curve, the sRGB encoding,
// 8 bits rounded), so its PNG of render's EXR is byte for byte the PNG render wrote beside it.
TEST_F(CliTools, ConvertWritesThePngRenderWritesBesideTheExr) {
  // Hand-made values, exact bytes (float arithmetic as in core/image.cpp):
  Image img(5, 1);
  img.at(0, 0) = Vec3(0.0f);
  img.at(1, 0) = Vec3(1.0f);
  img.at(2, 0) = Vec3(0.5f, 0.25f, 4.0f);
  img.at(3, 0) = Vec3(0.18f);
  img.at(4, 0) = Vec3(11.2f);
  scatterlab::writeExr(img, out("h.exr"));
  // linear: clamp at 1, then sRGB: 0.5 -> 1.055 * 0.5^(1/2.4) - 0.055 = 0.73535 -> 188.
  RunResult r = run("convert " + out("h.exr") + " " + out("lin.png") + " --tonemap linear");
  ASSERT_EQ(r.code, 0) << r.output;
  EXPECT_NE(r.output.find("wrote " + out("lin.png") + " (5x1, exposure 0, linear)"),
            std::string::npos)
      << r.output;
  Png p = readPng(out("lin.png"));
  ASSERT_EQ(p.width, 5);
  ASSERT_EQ(p.height, 1);
  EXPECT_EQ(p.at(0, 0), (std::array<int, 3>{0, 0, 0}));
  EXPECT_EQ(p.at(1, 0), (std::array<int, 3>{255, 255, 255}));
  // 0.25 is sRGB 0.53709 -> 137.46 -> 137; 4 clamps to 255.
  EXPECT_EQ(p.at(2, 0), (std::array<int, 3>{188, 137, 255}));
  // One stop up: 0.25 shows as 0.5 did.
  r = run("convert " + out("h.exr") + " " + out("ev.png") + " --tonemap linear --exposure 1");
  ASSERT_EQ(r.code, 0) << r.output;
  p = readPng(out("ev.png"));
  EXPECT_EQ(p.at(2, 0), (std::array<int, 3>{255, 188, 255}));
  // The default is render's: aces. 1 -> 2.54 / 3.16 = 0.80380 -> sRGB 0.90823 -> 232;
  // 0.18 -> 0.32048 -> sRGB 0.55542 -> 141.
  r = run("convert " + out("h.exr") + " " + out("aces.png"));
  ASSERT_EQ(r.code, 0) << r.output;
  p = readPng(out("aces.png"));
  EXPECT_EQ(p.at(0, 0), (std::array<int, 3>{0, 0, 0}));
  EXPECT_EQ(p.at(1, 0), (std::array<int, 3>{232, 232, 232}));
  EXPECT_EQ(p.at(3, 0), (std::array<int, 3>{141, 141, 141}));
  // filmic: Hable's curve normalised to its white 11.2 shows 11.2 as full white.
  r = run("convert " + out("h.exr") + " " + out("filmic.png") + " --tonemap filmic");
  ASSERT_EQ(r.code, 0) << r.output;
  p = readPng(out("filmic.png"));
  EXPECT_EQ(p.at(4, 0), (std::array<int, 3>{255, 255, 255}));
  EXPECT_EQ(p.at(0, 0), (std::array<int, 3>{0, 0, 0}));

  // A render's EXR converts to the very bytes of its own PNG, for the default and other
  // settings.
  const std::string scene = writeScene();
  for (const std::string opts : {"", " --tonemap filmic --exposure 1.5", " --tonemap linear"}) {
    r = run("render " + scene + " -q -o " + out("r.exr") + " --png " + out("r.png") + opts);
    ASSERT_EQ(r.code, 0) << r.output;
    r = run("convert " + out("r.exr") + " " + out("c.png") + opts);
    ASSERT_EQ(r.code, 0) << r.output;
    const Png rendered = readPng(out("r.png")), converted = readPng(out("c.png"));
    EXPECT_EQ(converted.width, 16);
    EXPECT_EQ(converted.height, 12);
    EXPECT_EQ(converted.rgb, rendered.rgb) << opts;
    int lit = 0;
    for (unsigned char b : converted.rgb) lit += b > 0;
    EXPECT_GT(lit, 0) << "an all-black image proves nothing" << opts;
  }
}

TEST_F(CliTools, ConvertBadInputs) {
  Image img(4, 3);
  for (Vec3& v : img.pixels()) v = Vec3(0.5f);
  scatterlab::writeExr(img, out("in.exr"));
  const std::string target = out("o.png");
  const std::string convert = "convert " + out("in.exr") + " ";
  // Usage errors (exit 2), each naming the option or argument.
  expectFails(convert + out("o.exr"), 2,
              {"output: '" + out("o.exr") + "' does not end in .png: convert writes PNG only",
               "an EXR is already the linear image"},
              out("o.exr"));
  expectFails(convert + out("o.jpg"), 2, {"does not end in .png"}, out("o.jpg"));
  for (const std::string ev : {"nan", "inf", "-inf", "101", "1e300", "bright", "''"})
    expectFails(convert + target + " --exposure " + ev, 2,
                {"--exposure", "is not a number of stops in [-100, 100]"}, target);
  expectFails(convert + target + " --tonemap reinhard", 2, {"--tonemap", "reinhard"}, target);
  expectFails("convert " + out("in.exr"), 2, {"output is required"}, target);
  // Bad input files (exit 1, as compare's), named.
  expectFails("convert " + out("missing.exr") + " " + target, 1,
              {"input '" + out("missing.exr") + "' does not exist"}, target);
  expectFails("convert " + dir_.string() + " " + target, 1, {"is a directory"}, target);
  // A PNG is recognised by its signature, whatever its name.
  ASSERT_EQ(run(convert + out("p.png")).code, 0);
  fs::copy_file(out("p.png"), out("disguised.exr"));
  for (const std::string& png : {out("p.png"), out("disguised.exr")})
    expectFails("convert " + png + " " + target, 1,
                {"input '" + png +
                 "' is a PNG (8-bit, display-encoded); convert reads linear OpenEXR images"},
                target);
  const std::string text = write("text.exr", "not an image at all");
  expectFails("convert " + text + " " + target, 1, {"cannot read EXR '" + text + "'"}, target);
  // Non-finite pixels would show as black (NaN) or white (inf): said, not hidden.
  img.at(2, 1) = Vec3(NAN, 0.5f, 0.5f);
  scatterlab::writeExr(img, out("nan.exr"));
  expectFails("convert " + out("nan.exr") + " " + target, 1,
              {"input '" + out("nan.exr") +
               "' has 1 non-finite channel value (1 NaN, 0 inf; the first at pixel (2, 1))"},
              target);
}

// compare used to print "cannot read EXR 'x.png': cannot parse the header: File is not an
// OpenEXR file: magic ..." for a PNG; now one line saying what the file is and what to give.
TEST_F(CliTools, CompareGivenAPngSaysWhatItNeeds) {
  Image img(4, 3);
  scatterlab::writeExr(img, out("a.exr"));
  scatterlab::writePng(img, out("a.png"));
  fs::copy_file(out("a.png"), out("b.exr"));  // a PNG under an EXR's name
  for (const auto& [args, what, file] :
       {std::tuple{out("a.png") + " " + out("a.exr"), "image", out("a.png")},
        std::tuple{out("a.exr") + " " + out("a.png"), "reference", out("a.png")},
        std::tuple{out("b.exr") + " " + out("a.exr"), "image", out("b.exr")}}) {
    expectFails("compare " + args + " --diff " + out("d.png"), 1,
                {std::string(what) + " '" + file +
                 "' is a PNG (8-bit, display-encoded); compare needs linear OpenEXR images (the "
                 ".exr that render -o writes; its PNGs are display copies)"},
                out("d.png"));
    EXPECT_EQ(run("compare " + args).output.find("magic"), std::string::npos);
  }
}

// --diff-signed writes the gallery's signed error map (experiment/error_map.h): per pixel the
// mean over channels of the sRGB-encoded difference, red where the image is brighter, blue
// where darker, full at 0.1, and the colour scale below it.
TEST_F(CliTools, CompareDiffSignedWritesTheGallerysErrorMapAndItsScale) {
  // 64 px wide: the bar's labels fit (55 px at font scale 1); bar 30 px high.
  Image ref(64, 2), img(64, 2);
  for (Vec3& v : ref.pixels()) v = Vec3(0.5f);
  img = ref;
  // Values on the linear piece of the sRGB curve (x 12.92 exactly below 0.0031308) where a
  // difference is wanted in display units.
  const auto display = [](float s) { return s / 12.92f; };
  ref.at(0, 0) = Vec3(0.0f), img.at(0, 0) = Vec3(1.0f);                   // +1: full red
  ref.at(1, 0) = Vec3(1.0f), img.at(1, 0) = Vec3(0.0f);                   // -1: full blue
  ref.at(2, 0) = Vec3(0.0f), img.at(2, 0) = Vec3(display(0.036f), 0, 0);  // +0.012: red 0.12
  ref.at(3, 0) = Vec3(0.0f), img.at(3, 0) = Vec3(display(0.02f));         // +0.02: red 0.2
  ref.at(4, 0) = Vec3(display(0.036f)), img.at(4, 0) = Vec3(0.0f);        // -0.036: blue 0.36
  scatterlab::writeExr(img, out("img.exr"));
  scatterlab::writeExr(ref, out("ref.exr"));
  const std::string images = out("img.exr") + " " + out("ref.exr");
  RunResult r = run("compare " + images + " --diff " + out("s.png") + " --diff-signed");
  ASSERT_EQ(r.code, 0) << r.output;
  EXPECT_NE(r.output.find("signed diff:       " + out("s.png") +
                          ": red = image brighter, blue = darker, full colour at a mean sRGB "
                          "channel difference of +-0.1 (PNG transform, exposure 0); scale bar "
                          "below"),
            std::string::npos)
      << r.output;
  const Png p = readPng(out("s.png"));
  ASSERT_EQ(p.width, 64);
  ASSERT_EQ(p.height, 2 + 4 + 30);
  using Rgb = std::array<int, 3>;
  EXPECT_EQ(p.at(0, 0), (Rgb{255, 0, 0}));
  EXPECT_EQ(p.at(1, 0), (Rgb{0, 0, 255}));
  EXPECT_EQ(p.at(2, 0), (Rgb{31, 0, 0}));  // 0.12 x 255 = 30.6
  EXPECT_EQ(p.at(3, 0), (Rgb{51, 0, 0}));  // 0.2 x 255 = 51
  EXPECT_EQ(p.at(4, 0), (Rgb{0, 0, 92}));  // 0.36 x 255 = 91.8
  for (int x = 5; x < 64; ++x) EXPECT_EQ(p.at(x, 0), (Rgb{0, 0, 0})) << x;
  for (int x = 0; x < 64; ++x) EXPECT_EQ(p.at(x, 1), (Rgb{0, 0, 0})) << x;
  for (int y = 2; y < 6; ++y) EXPECT_EQ(p.at(10, y), (Rgb{0, 0, 0})) << "the gap, row " << y;
  // The bar (rows 12..17 of the 30 under the gap): blue -0.1 at the left, red +0.1 at the
  // right, black in the middle, a white line above and below.
  EXPECT_EQ(p.at(0, 6 + 14), (Rgb{0, 0, 255}));
  EXPECT_EQ(p.at(63, 6 + 14), (Rgb{255, 0, 0}));
  EXPECT_EQ(p.at(31, 6 + 14)[0] + p.at(31, 6 + 14)[1], 0);
  EXPECT_LE(p.at(31, 6 + 14)[2], 5);  // 1/63 of full: sRGB 0.016 -> 4
  EXPECT_EQ(p.at(20, 6 + 11), (Rgb{255, 255, 255}));
  EXPECT_EQ(p.at(20, 6 + 18), (Rgb{255, 255, 255}));
  int labelPixels = 0;  // "-0.1", "0", "+0.1" in white below the bar
  for (int y = 6 + 21; y < 6 + 28; ++y)
    for (int x = 0; x < 64; ++x) labelPixels += p.at(x, y) == Rgb{255, 255, 255};
  EXPECT_GT(labelPixels, 20);

  r = run("compare " + images + " --diff " + out("j.png") + " --diff-signed --json");
  ASSERT_EQ(r.code, 0) << r.output;
  Json j = Json::parse(r.output);
  EXPECT_EQ(j["diff"]["file"], out("j.png"));
  EXPECT_EQ(j["diff"]["signed"], true);
  EXPECT_EQ(j["diff"]["full_scale"], 0.1);
  EXPECT_EQ(readPng(out("j.png")).rgb, p.rgb);

  // The default stays |image - reference| per channel, white at the largest difference (1).
  r = run("compare " + images + " --diff " + out("u.png") + " --json");
  ASSERT_EQ(r.code, 0) << r.output;
  j = Json::parse(r.output);
  EXPECT_EQ(j["diff"]["signed"], false);
  EXPECT_EQ(j["diff"]["multiplier"], 1.0);
  EXPECT_EQ(j["diff"]["white_at"], 1.0);
  const Png u = readPng(out("u.png"));
  ASSERT_EQ(u.width, 64);
  ASSERT_EQ(u.height, 2);
  EXPECT_EQ(u.at(0, 0), (Rgb{255, 255, 255}));
  EXPECT_EQ(u.at(1, 0), (Rgb{255, 255, 255}));
  EXPECT_EQ(u.at(5, 0), (Rgb{0, 0, 0}));
  r = run("compare " + images + " --diff " + out("t.png") + " --diff-scale 4");
  ASSERT_EQ(r.code, 0) << r.output;
  EXPECT_NE(r.output.find("diff:              " + out("t.png") +
                          ": |image - reference| x 4, white at 0.25 (linear)"),
            std::string::npos)
      << r.output;

  // Usage errors.
  expectFails("compare " + images + " --diff-signed", 2, {"--diff-signed requires --diff"},
              out("none.png"));
  expectFails("compare " + images + " --diff " + out("x.png") + " --diff-signed --diff-scale 2", 2,
              {"--diff-scale excludes --diff-signed"}, out("x.png"));
  // Images of different sizes: compare's own error, and no map.
  scatterlab::writeExr(Image(8, 2), out("small.exr"));
  expectFails("compare " + out("small.exr") + " " + out("ref.exr") + " --diff " + out("y.png") +
                  " --diff-signed",
              1, {"8x2", "64x2"}, out("y.png"));
}

// -r WxH is --set camera.width=W --set camera.height=H (vdb_render's -res).
TEST_F(CliTools, RenderResolutionShorthand) {
  const std::string scene = writeScene();
  RunResult r =
      run("render " + scene + " -q -o " + out("a.exr") + " -r 20x14 --stats " + out("a.json"));
  ASSERT_EQ(r.code, 0) << r.output;
  const Json stats = Json::parse(std::ifstream(out("a.json")));
  EXPECT_EQ(stats["width"], 20);
  EXPECT_EQ(stats["height"], 14);
  r = run("render " + scene + " -q -o " + out("b.exr") +
          " --set camera.width=20 --set camera.height=14");
  ASSERT_EQ(r.code, 0) << r.output;
  const Image a = scatterlab::readExr(out("a.exr")), b = scatterlab::readExr(out("b.exr"));
  EXPECT_EQ(a.width(), 20);
  EXPECT_EQ(a.height(), 14);
  EXPECT_EQ(a.pixels(), b.pixels());
  r = run("render " + scene + " -q -o " + out("c.exr") + " --resolution 7X5");
  ASSERT_EQ(r.code, 0) << r.output;
  EXPECT_EQ(scatterlab::readExr(out("c.exr")).width(), 7);
  EXPECT_EQ(scatterlab::readExr(out("c.exr")).height(), 5);
  // Other --set keys go along with it.
  r = run("render " + scene + " -q -o " + out("d.exr") + " -r 8x6 --set camera.spp=4");
  ASSERT_EQ(r.code, 0) << r.output;
  EXPECT_EQ(scatterlab::readExr(out("d.exr")).width(), 8);

  const std::string o = out("o.exr");
  for (const std::string bad : {"0x10", "10x0", "10", "axb", "10x10x10", "x10", "10x", "16385x10",
                                "10x99999999999", "1.5x2", "+3x4", "' 3x4'", "''"})
    expectFails("render " + scene + " -o " + o + " -r " + bad, 2,
                {"--resolution",
                 "is not a resolution: expected WxH with whole numbers from 1 "
                 "to 16384, e.g. 640x480"},
                o);
  // The largest side the camera keys allow passes -r's check (the output's missing directory
  // then stops the run before any render).
  r = run("render " + scene + " -o " + out("nodir/o.exr") + " -r 16384x1");
  EXPECT_EQ(r.code, 1) << r.output;
  EXPECT_NE(r.output.find("nodir"), std::string::npos) << r.output;
  EXPECT_EQ(r.output.find("is not a resolution"), std::string::npos) << r.output;
  // Both -r and a --set of the size: an error naming both.
  for (const std::string set :
       {"camera.width=8", "camera.height=8", "'camera={\"position\": [0.5,0.5,-2]}'"})
    expectFails("render " + scene + " -o " + o + " -r 20x14 --set " + set, 2,
                {"--resolution 20x14 and --set camera", "both set the image size; give one"}, o);
}

namespace {

/// A stand-in for ffmpeg (the test machines have none): it checks that every frame the pattern
/// names exists, records its arguments, and writes "fake FORMAT N frames at RATE" to its output
/// (the last argument); with FAIL set it prints ffmpeg-like errors and exits 3 instead.
std::string fakeFfmpeg(const fs::path& dir, bool fail) {
  const fs::path p = dir / (fail ? "ffmpeg-failing" : "ffmpeg");
  std::ofstream(p) << "#!/bin/sh\n"
                   << "echo \"$@\" > \"" << (dir / "ffmpeg.args").string() << "\"\n"
                   << (fail ? "echo \"Unknown encoder 'libx264'\" >&2\n"
                              "echo 'Error selecting an encoder' >&2\nexit 3\n"
                            : "")
                   << "rate=''; pattern=''; count=''; format=''; out=''\n"
                   << "while [ $# -gt 0 ]; do\n"
                   << "  case \"$1\" in\n"
                   << "    -framerate) rate=$2; shift;;\n"
                   << "    -i) pattern=$2; shift;;\n"
                   << "    -frames:v) count=$2; shift;;\n"
                   << "    -f) format=$2; shift;;\n"
                   << "  esac\n"
                   << "  out=$1; shift\n"
                   << "done\n"
                   << "d=$(dirname \"$pattern\"); n=0\n"
                   << "while [ $n -lt \"$count\" ]; do\n"
                   << "  f=$(printf \"$d/frame%06d.png\" $n)\n"
                   << "  [ -s \"$f\" ] || { echo \"missing $f\" >&2; exit 4; }\n"
                   << "  mkdir -p \"" << (dir / "seen").string() << "\"\n"
                   << "  cp \"$f\" \"" << (dir / "seen").string() << "\"\n"
                   << "  n=$((n + 1))\n"
                   << "done\n"
                   << "echo \"fake $format $count frames at $rate\" > \"$out\"\n";
  fs::permissions(p, fs::perms::owner_all);
  return p.string();
}

/// Sets an environment variable for its scope.
struct ScopedEnv {
  ScopedEnv(const char* name, const std::string& value) : name_(name) {
    ::setenv(name, value.c_str(), 1);
  }
  ~ScopedEnv() { ::unsetenv(name_); }
  const char* name_;
};

}  // namespace

// `render --frames A:B --movie OUT` encodes the frames, as PNGs in a directory of its own, through
// ffmpeg at --fps, after every frame rendered and before anything is committed; the directory is
// gone afterwards. (Checked by hand with Debian's ffmpeg 5.1, 2026-11-28: .mp4, .mkv and .mov
// H.264 padded to even sizes, .webm VP9, .gif, 6 frames at 6 fps each, ffprobe.)
TEST_F(CliTools, RenderMovieEncodesTheFramesThroughFfmpeg) {
  const std::string scene = writeScene();
  const ScopedEnv env("SCATTERLAB_FFMPEG", fakeFfmpeg(dir_, false));
  const std::string movie = out("m.mp4");
  const RunResult r =
      run("render " + scene + " -o " + out("f.exr") + " --frames 2:4 --fps 12 --movie " + movie);
  ASSERT_EQ(r.code, 0) << r.output;
  std::ifstream in(movie);
  std::string content((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  EXPECT_EQ(content, "fake mp4 3 frames at 12\n");
  for (const char* f : {"f.0002.exr", "f.0003.exr", "f.0004.exr"}) EXPECT_TRUE(fs::exists(out(f)));
  EXPECT_NE(r.output.find(movie), std::string::npos) << r.output;
  std::ifstream argsFile(dir_ / "ffmpeg.args");
  std::string args((std::istreambuf_iterator<char>(argsFile)), std::istreambuf_iterator<char>());
  for (const char* a : {"-framerate 12 ", "-c:v libx264 -pix_fmt yuv420p", "-frames:v 3", "-f mp4"})
    EXPECT_NE(args.find(a), std::string::npos) << a << " in " << args;
  const std::size_t i = args.find("-i ") + 3;
  const fs::path frames = fs::path(args.substr(i, args.find(' ', i) - i)).parent_path();
  EXPECT_FALSE(fs::exists(frames)) << frames << " left behind";
  // .webm: VP9.
  ASSERT_EQ(
      run("render " + scene + " -o " + out("g.exr") + " --frames 0:1 --movie " + out("m.webm"))
          .code,
      0);
  std::ifstream webmArgs(dir_ / "ffmpeg.args");
  std::string wa((std::istreambuf_iterator<char>(webmArgs)), std::istreambuf_iterator<char>());
  EXPECT_NE(wa.find("-c:v libvpx-vp9"), std::string::npos) << wa;
  EXPECT_NE(wa.find("-f webm"), std::string::npos) << wa;
  // With --png the movie's frames are those PNGs, byte for byte (encoded once, then linked).
  ASSERT_EQ(run("render " + scene + " -o " + out("h.exr") + " --frames 0:1 --png " + out("h.png") +
                " --movie " + out("h.mp4"))
                .code,
            0);
  for (const char* f : {"0000", "0001"}) {
    const std::string seen = dir_ / "seen" / ("frame00000" + std::string(1, f[3]) + ".png");
    EXPECT_EQ(scatterlab::testing::readBytes(seen),
              scatterlab::testing::readBytes(out("h." + std::string(f) + ".png")))
        << f;
  }
}

TEST_F(CliTools, RenderMovieBadInputs) {
  const std::string scene = writeScene();
  const std::string f = out("f.exr");
  expectFails("render " + scene + " -o " + f + " --movie " + out("m.mp4"), 2,
              {"--movie", "--frames"}, out("m.mp4"));
  expectFails("render " + scene + " -o " + f + " --frames 0:1 --movie " + out("m.avi"), 2,
              {"'" + out("m.avi") + "' has no movie extension"}, out("m.avi"));
  {
    const ScopedEnv env("SCATTERLAB_FFMPEG", out("no-such-ffmpeg"));
    expectFails("render " + scene + " -o " + f + " --frames 0:1 --movie " + out("m.mp4"), 1,
                {"SCATTERLAB_FFMPEG", "is not an executable file"}, out("f.0000.exr"));
  }
  {
    const ScopedEnv env("PATH", dir_.string() + "/empty");
    expectFails("render " + scene + " -o " + f + " --frames 0:1 --movie " + out("m.mp4"), 1,
                {"--movie needs ffmpeg", "apt-get install ffmpeg"}, out("f.0000.exr"));
  }
  // ffmpeg fails: its status and messages, and no frame and no movie (all or nothing).
  const ScopedEnv env("SCATTERLAB_FFMPEG", fakeFfmpeg(dir_, true));
  expectFails("render " + scene + " -q -o " + f + " --frames 0:1 --movie " + out("m.mp4"), 1,
              {"exited with status 3", "Unknown encoder 'libx264'", "Error selecting"},
              out("m.mp4"));
  EXPECT_FALSE(fs::exists(out("f.0000.exr")));
}
