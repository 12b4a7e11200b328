// Regression tests of issue 17 (inputs that crashed or misbehaved): strict JSON, values beyond
// single precision, degenerate cameras, far-away points, NaN-safe grid lookups.

#include <gtest/gtest.h>

#include <OpenEXR/ImfChannelList.h>
#include <OpenEXR/ImfFrameBuffer.h>
#include <OpenEXR/ImfHeader.h>
#include <OpenEXR/ImfOutputFile.h>
#include <OpenEXR/ImfTiledRgbaFile.h>
#include <signal.h>
#include <unistd.h>

#include <chrono>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <functional>
#include <iterator>
#include <limits>
#include <string>

#include "core/atomic_file.h"
#include "core/grid.h"
#include "core/image.h"
#include "core/limits.h"
#include "core/params.h"
#include "support/scenes.h"

using namespace scatterlab;
using scatterlab::testing::sceneFromJson;

namespace {

Json validDoc() {
  return Json::parse(R"({
    "medium": {"bounds": {"min": [0,0,0], "max": [1,1,1]},
               "density": {"type": "gaussians", "blobs": [{"center": [0.5,0.5,0.5], "radius": 0.2, "weight": 1.0}]},
               "resolution": 8},
    "lights": [{"type": "point", "position": [0.5,1.4,0.5], "intensity": [4,4,4]}],
    "camera": {"position": [0.5,0.5,-2], "look_at": [0.5,0.5,0.5], "up": [0,1,0],
               "width": 8, "height": 6}})");
}

/// The message of the error `f` throws (type E), or "" when it throws nothing.
template <class E, class F>
std::string messageOf(F&& f) {
  try {
    f();
  } catch (const E& e) {
    return e.what();
  }
  return "";
}

/// Applies `--set` assignments to the valid document and parses it; returns the ConfigError.
std::string sceneError(std::initializer_list<std::string> sets) {
  Json doc = validDoc();
  for (const auto& s : sets) applyOverride(doc, s);
  return messageOf<ConfigError>([&] { sceneFromJson(doc); });
}

bool has(const std::string& text, const std::string& part) {
  return text.find(part) != std::string::npos;
}

}  // namespace

/// The LimitError message of parsing the valid document with `sets` applied, "" when none.
static std::string limitMessage(std::initializer_list<const char*> sets) {
  Json doc = validDoc();
  for (const char* a : sets) applyOverride(doc, a);
  return messageOf<LimitError>([&] { sceneFromJson(doc); });
}

TEST(StrictJson, DepthLimitIsAClearErrorNotAStackOverflow) {
  const auto nested = [](int n) { return std::string(n, '[') + std::string(n, ']'); };
  EXPECT_EQ(parseJson(nested(kMaxJsonDepth), "x").size(), 1u);  // 64 levels are fine
  const std::string e65 = messageOf<IoError>([&] { parseJson(nested(kMaxJsonDepth + 1), "'a'"); });
  EXPECT_TRUE(has(e65, "'a': nesting deeper than 64")) << e65;
  // 100 000 levels crashed the JSON library (recursion while dumping into the message).
  const std::string deep = messageOf<IoError>([&] { parseJson(nested(100000), "'deep.json'"); });
  EXPECT_TRUE(has(deep, "'deep.json': nesting deeper than 64")) << deep;
  const std::string unclosed =
      messageOf<IoError>([&] { parseJson(std::string(100000, '{'), "'u.json'"); });
  EXPECT_TRUE(has(unclosed, "'u.json'")) << unclosed;
}

TEST(StrictJson, DuplicateKeysOverflowAndSyntaxNameTheOrigin) {
  const std::string dup =
      messageOf<IoError>([] { parseJson(R"({"a": {"b": 1, "b": 2}})", "'s'"); });
  EXPECT_TRUE(has(dup, "'s': duplicate key \"b\"")) << dup;
  // The same key in sibling objects is fine.
  EXPECT_EQ(parseJson(R"([{"b": 1}, {"b": 2}])", "s")[1]["b"], 2);
  const std::string big = messageOf<IoError>([] { parseJson(R"({"a": 1e400})", "'big.json'"); });
  EXPECT_TRUE(has(big, "'big.json': number overflow parsing '1e400'")) << big;
  const std::string syntax = messageOf<IoError>([] { parseJson("{\"a\": ,}", "'bad.json'"); });
  EXPECT_TRUE(has(syntax, "'bad.json': malformed JSON")) << syntax;
  EXPECT_FALSE(has(syntax, "json.exception")) << syntax;
  EXPECT_EQ(parseJson("// comment\n{\"a\": 2}", "s")["a"], 2);
}

TEST(StrictJson, SetRejectsDeepPathsAndValuesButKeepsStrings) {
  Json doc = Json::object();
  std::string path;
  for (int i = 0; i < 100; ++i) path += "a.";
  EXPECT_TRUE(
      has(messageOf<ConfigError>([&] { applyOverride(doc, path + "b=1"); }), "deeper than 64"));
  EXPECT_TRUE(has(messageOf<IoError>([&] {
                    applyOverride(doc, "x=" + std::string(70, '[') + std::string(70, ']'));
                  }),
                  "nesting deeper than 64"));
  applyOverride(doc, "name=plain text");
  EXPECT_EQ(doc["name"], "plain text");
  applyOverride(doc, "n=1e400");  // not JSON (out of double range): kept as the string
  EXPECT_EQ(doc["n"], "1e400");
}

TEST(FiniteValues, NumbersBeyondSinglePrecisionNameTheKey) {
  // Each of these rendered inf/NaN images with exit 0 or crashed (exit 139) before.
  EXPECT_TRUE(has(sceneError({"camera.position=[0.5,0.5,-1e39]"}), "'camera.position'"));
  EXPECT_TRUE(has(sceneError({"camera.up=[0,1e300,0]"}), "beyond single precision"));
  EXPECT_TRUE(has(sceneError({"background=1e39"}), "'background': value 1e+39 is beyond"));
  const std::string i =
      sceneError({R"(lights=[{"type":"point","position":[0.5,2,0.5],"intensity":1e39}])"});
  EXPECT_TRUE(has(i, "'lights[0].intensity'")) << i;
  const std::string w = sceneError(
      {R"(medium.density={"type":"gaussians","blobs":[{"center":[0.5,0.5,0.5],"radius":0.2,"weight":1e39}]})"});
  EXPECT_TRUE(has(w, "weight")) << w;
  // Finite in float, but |x|² overflows float: ~1e20 ended in a wild read.
  const std::string far = sceneError({"camera.position=[1e20,0.5,-2]"});
  EXPECT_TRUE(has(far, "'camera.position'") && has(far, "box diagonals")) << far;
  EXPECT_TRUE(
      has(sceneError({R"(lights=[{"type":"point","position":[0.5,3e7,0.5],"intensity":1}])"}),
          "'lights[0].position'"));
  // 1e6 diagonals is the bound: 1.7e6 units from a unit box's centre is allowed.
  EXPECT_EQ(sceneError({"camera.position=[0.5,0.5,-1.7e6]"}), "");
  EXPECT_TRUE(has(sceneError({"medium.bounds.max=[1,1,1e16]"}), "beyond +-1e15"));
  EXPECT_TRUE(has(sceneError({"medium.bounds.max=[1,1,1e-9]"}), "too thin"));
}

TEST(FiniteValues, IntegersBeyondLongLongAreReportedAsWritten) {
  const std::string e = sceneError({"camera.width=18446744073709551615"});
  EXPECT_TRUE(has(e, "18446744073709551615")) << e;
  EXPECT_FALSE(has(e, "-1 ")) << e;
}

TEST(CameraDegeneracies, AreRejectedAtParseTime) {
  EXPECT_TRUE(has(sceneError({"camera.look_at=[0.5,0.5,-2]"}), "'camera.look_at'"));
  EXPECT_TRUE(has(sceneError({"camera.up=[0,0,1]"}), "'camera.up': must not be parallel"));
  EXPECT_TRUE(has(sceneError({"camera.up=[0,0,0]"}), "'camera.up': must not be the zero"));
  // Nearly parallel (1e-5 rad) is refused; 0.1 rad off is fine.
  EXPECT_TRUE(has(sceneError({"camera.up=[0,1e-5,1]"}), "parallel"));
  EXPECT_EQ(sceneError({"camera.up=[0,0.1,1]"}), "");
  // A huge but finite up is normalised in double: accepted and a unit vector.
  Json doc = validDoc();
  applyOverride(doc, "camera.up=[0,1e30,0]");
  const Scene s = sceneFromJson(doc);
  EXPECT_FLOAT_EQ(glm::length(s.camera.up), 1.0f);
  Vec3 f, r, u;
  s.camera.frame(f, r, u);
  EXPECT_NEAR(u.y, 1.0f, 1e-6f);
}

TEST(GridLookups, NonFiniteCoordinatesReadAnEdgeVoxelNotMemory) {
  // 2x2x2 grid with distinct corners: value = i + 2j + 4k.
  DensityGrid g(Box{Vec3(0), Vec3(1)}, IVec3(2));
  for (int k = 0; k < 2; ++k)
    for (int j = 0; j < 2; ++j)
      for (int i = 0; i < 2; ++i) g.at(i, j, k) = float(i + 2 * j + 4 * k);
  const float nan = std::numeric_limits<float>::quiet_NaN();
  const float inf = std::numeric_limits<float>::infinity();
  EXPECT_EQ(g.sampleIndex(Vec3(nan)), 0.0f);
  EXPECT_EQ(g.sampleIndex(Vec3(-inf)), 0.0f);
  EXPECT_EQ(g.sampleIndex(Vec3(inf)), 7.0f);
  EXPECT_EQ(g.sampleIndex(Vec3(1e30f, nan, -1e30f)), 1.0f);
  EXPECT_EQ(g.sampleIndex(Vec3(0.5f, 0.0f, 0.0f)), 0.5f);
  EXPECT_EQ(g.sample(Vec3(nan)), 0.0f);  // outside the box: zero
}

TEST(StrictJson, InvalidUtf8InASetValueIsDescribedNotThrown) {
  // Found by fuzz/fuzz_set.cpp: a --set VALUE that is not JSON (here: not UTF-8) is kept as a
  // string, and describing it in a message threw json type_error 316 ("internal error").
  const std::string e = sceneError({"lights=[{\"\x88\x86pe\":\"point\"}]"});
  EXPECT_TRUE(has(e, "'lights'")) << e;
  Json doc = Json::object();
  applyOverride(doc, "name=\x88\x86");
  EXPECT_NO_THROW(describeValue(doc));
}

TEST(ResourceLimits, MemorySizesParseWithUnitsAndPercentages) {
  EXPECT_EQ(parseMemorySize("4G", "x"), std::uint64_t(4) << 30);
  EXPECT_EQ(parseMemorySize("512M", "x"), std::uint64_t(512) << 20);
  EXPECT_EQ(parseMemorySize("1.5GiB", "x"), std::uint64_t(3) << 29);
  EXPECT_EQ(parseMemorySize("2097152", "x"), std::uint64_t(2) << 20);
  EXPECT_EQ(parseMemorySize("100%", "x") / 4 * 3, defaultMemoryLimit());
  for (const char* bad : {"", "G", "-1G", "12Q", "0.5K", "101%", "nan", "1e30T"})
    EXPECT_THROW(parseMemorySize(bad, "--memory-limit"), ConfigError) << bad;
  EXPECT_EQ(formatBytes(1.5 * (1 << 30)), "1.5 GiB");
  EXPECT_EQ(formatBytes(100), "100 bytes");
}

/// Sets the memory limit for one test and restores the default afterwards.
struct MemoryLimit {
  explicit MemoryLimit(std::uint64_t bytes) { setMemoryLimit(bytes); }
  ~MemoryLimit() { setMemoryLimit(0); }
};

TEST(ResourceLimits, VolumesImagesAndSamplesAreRefusedBeforeAllocating) {
  const MemoryLimit limit(std::uint64_t(64) << 20);
  const std::string vol = limitMessage({"medium.resolution=512"});
  EXPECT_NE(vol.find("'medium.resolution': the density volume of 512x512x512 voxels needs about "
                     "512 MiB, above the memory limit of 64 MiB"),
            std::string::npos)
      << vol;
  const std::string img = limitMessage({"camera.width=8192", "camera.height=4096"});
  EXPECT_NE(img.find("'camera.width', 'camera.height': an image of 8192x4096 pixels"),
            std::string::npos)
      << img;
  EXPECT_NE(img.find("needs about 1.0 GiB"), std::string::npos) << img;
  // The grid itself checks too (a volume built from code, not from a key).
  EXPECT_THROW(DensityGrid(Box{Vec3(0), Vec3(1)}, IVec3(512, 512, 128)), LimitError);
  // Under the limit nothing changes.
  EXPECT_EQ(limitMessage({"medium.resolution=64"}), "");
}

TEST(ResourceLimits, TheDefaultIsThreeQuartersOfPhysicalMemory) {
  setMemoryLimit(0);
  if (std::getenv("SCATTERLAB_MEMORY_LIMIT") == nullptr) {
    EXPECT_EQ(memoryLimit(), defaultMemoryLimit());
  }
  const long pages = sysconf(_SC_PHYS_PAGES), page = sysconf(_SC_PAGE_SIZE);
  EXPECT_EQ(defaultMemoryLimit(), std::uint64_t(pages) * std::uint64_t(page) / 4 * 3);
}

// SIGINT while an output is being written: the handler removes the temporary, then the
// process dies by the signal as it would have (no output, no leftover).
TEST(SignalCleanup, InterruptDuringAWriteLeavesNoTemporary) {
  const std::filesystem::path dir =
      std::filesystem::temp_directory_path() / ("scatterlab_sigint_" + std::to_string(getpid()));
  std::filesystem::remove_all(dir);
  std::filesystem::create_directories(dir);
  const std::string out = (dir / "o.exr").string();
  EXPECT_EXIT(
      {
        removeTemporariesOnSignal();
        writeFileAtomically(out, [&](std::ostream& os) {
          os << std::string(100000, 'x');
          os.flush();
          // The temporary exists now, with contents.
          for (const auto& e : std::filesystem::directory_iterator(dir))
            if (std::filesystem::file_size(e.path()) == 0) std::_Exit(3);
          raise(SIGINT);
        });
        std::_Exit(4);
      },
      ::testing::KilledBySignal(SIGINT), "");
  EXPECT_TRUE(std::filesystem::is_empty(dir));
  std::filesystem::remove_all(dir);
}

// fuzz_exr's finding: a data window of 4325382x769 pixels in a 0.4 KB file made readExr
// allocate 40 GB (ASan: out of memory; without ASan the allocation's luck decided). Now the
// window is checked in 64 bits and its memory against the limit, before allocating.
TEST(BinaryInputs, ExrWithANegativeDataWindowOriginIsReadWhole) {
  // fuzz_exr found a 1x1 data window at (-1, -1): `base - origin * stride` in unsigned pointer
  // arithmetic overflowed (UBSan). The input is read now (its pixels are garbage: an IoError
  // is fine, a sanitizer report is not).
  try {
    (void)readExr(SCATTERLAB_SOURCE_DIR "/fuzz/regressions/fuzz_exr_negative_window_origin.exr");
  } catch (const IoError&) {
  }
  // A valid 3x2 window at (-2, -3): every pixel comes back in its place.
  const std::string p = (std::filesystem::temp_directory_path() /
                         ("scatterlab_negwin_" + std::to_string(getpid()) + ".exr"))
                            .string();
  const Imath::Box2i dw(Imath::V2i(-2, -3), Imath::V2i(0, -2));
  std::vector<float> rgb(3 * 2 * 3);
  for (std::size_t i = 0; i < rgb.size(); ++i) rgb[i] = float(i);
  {
    Imf::Header header(Imath::Box2i(Imath::V2i(0, 0), Imath::V2i(7, 7)), dw);
    Imf::FrameBuffer fb;
    for (int c = 0; c < 3; ++c) {
      header.channels().insert(std::string(1, "RGB"[c]), Imf::Channel(Imf::FLOAT));
      fb.insert(std::string(1, "RGB"[c]), Imf::Slice::Make(Imf::FLOAT, rgb.data() + c, dw, 12, 36));
    }
    Imf::OutputFile out(p.c_str(), header);
    out.setFrameBuffer(fb);
    out.writePixels(2);
  }
  const Image img = readExr(p);
  std::filesystem::remove(p);
  ASSERT_EQ(img.width(), 3);
  ASSERT_EQ(img.height(), 2);
  for (std::size_t k = 0; k < 6; ++k)
    EXPECT_EQ(img.pixels()[k], Vec3(float(3 * k), float(3 * k + 1), float(3 * k + 2))) << k;
}

TEST(BinaryInputs, ExrAttributeSizesAreCheckedAgainstTheFile) {
  // fuzz_exr (10-minute run): a 721-byte file whose attribute announces 1912602633 bytes;
  // OpenEXR allocated it before reading (1.9 GB resident, libFuzzer's out-of-memory).
  const std::string p = SCATTERLAB_SOURCE_DIR "/fuzz/regressions/fuzz_exr_huge_attribute.exr";
  const std::string m = messageOf<IoError>([&] { readExr(p); });
  EXPECT_TRUE(has(m, "cannot read EXR '" + p + "': header: attribute 'sca???")) << m;
  EXPECT_TRUE(has(m, "' announces 1912602633 bytes, beyond the end of the file (721 bytes)")) << m;
}

TEST(BinaryInputs, ExrChunkAnnouncingGigabytesIsAnErrorNamingTheFile) {
  // fuzz_exr (third 10-minute run): a 308-byte file on which OpenEXR allocated 1694498816 bytes
  // (ASan: past 2 GiB resident). Its channel list runs past the list's announced 73 bytes;
  // OpenEXR reads a chlist to its empty name, not by the size, so it went on from another byte
  // than the size walk and read an "attribute" of 1.69 GB there. The walk now requires known
  // types to have their layouts' sizes, so both read the same bytes.
  const std::string p = SCATTERLAB_SOURCE_DIR "/fuzz/regressions/fuzz_exr_chlist_overrun.exr";
  const std::string m = messageOf<IoError>([&] { readExr(p); });
  EXPECT_EQ(m, "cannot read EXR '" + p +
                   "': header: attribute 'channels' (a channel list) does not end within its 73 "
                   "bytes");
}

TEST(BinaryInputs, ExrWithAHugeDataWindowIsRefusedBeforeAllocating) {
  const std::string p = SCATTERLAB_SOURCE_DIR "/fuzz/regressions/fuzz_exr_huge_data_window.exr";
  const std::string m = messageOf<LimitError>([&] { readExr(p); });
  EXPECT_TRUE(has(m, "'" + p + "': an image of 4325382x769 pixels needs about 50 GiB")) << m;
}

namespace {

/// `exr` (a single-part scanline file) rebuilt with each chunk's payload replaced by
/// `payload(index, bytes)`; the offset table is rewritten so that the file stays well formed.
std::string rewriteExrChunks(const std::string& exr,
                             const std::function<std::string(int, const std::string&)>& payload) {
  std::ifstream in(exr, std::ios::binary);
  const std::string b((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  std::size_t p = 8;  // magic and version; then attributes (name, type, int32 size, value)
  while (b.at(p) != '\0') {
    p = b.find('\0', b.find('\0', p) + 1) + 1;
    std::int32_t size = 0;
    std::memcpy(&size, b.data() + p, 4);
    p += 4 + std::size_t(size);
  }
  ++p;
  std::uint64_t firstChunk = 0;
  std::memcpy(&firstChunk, b.data() + p, 8);
  const int chunks = int((firstChunk - p) / 8);
  std::string out = b.substr(0, p + 8 * std::size_t(chunks));
  for (int i = 0; i < chunks; ++i) {
    std::uint64_t at = 0;
    std::memcpy(&at, b.data() + p + 8 * std::size_t(i), 8);
    std::int32_t size = 0;
    std::memcpy(&size, b.data() + at + 4, 4);
    const std::string data = payload(i, b.substr(at + 8, std::size_t(size)));
    const std::uint64_t now = out.size();
    std::memcpy(out.data() + p + 8 * std::size_t(i), &now, 8);
    const std::int32_t newSize = std::int32_t(data.size());
    out.append(b, at, 4).append(reinterpret_cast<const char*>(&newSize), 4).append(data);
  }
  return out;
}

Image rampImage(int w, int h) {
  Image img(w, h);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) img.at(x, y) = Vec3(float(x), float(y), 0.5f);
  return img;
}

std::string tempPath(const std::string& name) {
  return (std::filesystem::temp_directory_path() /
          ("scatterlab_" + std::to_string(getpid()) + "_" + name))
      .string();
}

}  // namespace

// Issue 37: a valid header whose chunks hold 0 bytes was read as OpenEXR's uninitialised line
// buffer (`compare e.exr e.exr` reported 100 % error; one file read twice differed). The core
// reader checks every chunk; the error names the file and the first line without pixels.
TEST(BinaryInputs, ExrChunksWithoutPixelDataAreAnErrorNamingTheFirstLine) {
  const std::string good = tempPath("chunks.exr"), bad = tempPath("empty_chunks.exr");
  writeExr(rampImage(8, 40), good);  // ZIP, 16 lines per chunk: chunks at lines 0, 16, 32
  {
    std::ofstream(bad, std::ios::binary)
        << rewriteExrChunks(good, [](int, const std::string&) { return std::string(); });
  }
  std::string m = messageOf<IoError>([&] { readExr(bad); });
  EXPECT_TRUE(has(m, "cannot read EXR '" + bad +
                         "': line 0 (data window lines 0 to 39) has no "
                         "valid pixel data"))
      << m;
  // Only the second chunk empty: the first 16 lines were fine, the error names line 16.
  {
    std::ofstream(bad, std::ios::binary) << rewriteExrChunks(
        good, [](int i, const std::string& d) { return i == 1 ? std::string() : d; });
  }
  m = messageOf<IoError>([&] { readExr(bad); });
  EXPECT_TRUE(has(m, "': line 16 (data window lines 0 to 39) has no valid pixel data")) << m;
  // A chunk whose zlib stream is valid but one byte short decompresses to too few bytes: OpenEXR's
  // C++ reader filled the rest from its buffer; here it is an error. (The last zlib byte is part
  // of the checksum, so the stream is cut before it.)
  {
    std::ofstream(bad, std::ios::binary) << rewriteExrChunks(
        good, [](int i, const std::string& d) { return i == 2 ? d.substr(0, d.size() - 1) : d; });
  }
  m = messageOf<IoError>([&] { readExr(bad); });
  EXPECT_TRUE(has(m, "': line 32 (data window lines 0 to 39) has no valid pixel data")) << m;
  // The unchanged file reads back exactly.
  EXPECT_EQ(readExr(good).pixels(), rampImage(8, 40).pixels());
  std::filesystem::remove(good);
  std::filesystem::remove(bad);
}

// The core reader's other paths: tiles (their chunks placed by tile, inside an offset data
// window) and half channels converted to float.
TEST(BinaryInputs, ExrTiledHalfFilesReadEveryPixelInPlace) {
  const std::string p = tempPath("tiled_half.exr");
  const Imath::Box2i dw(Imath::V2i(-3, 5), Imath::V2i(6, 11));  // 10x7, tiles of 4x3
  const int w = 10, h = 7;
  std::vector<Imf::Rgba> px(std::size_t(w) * h);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) px[std::size_t(y) * w + x] = Imf::Rgba(x, y, 0.25f, 0.5f);
  {
    Imf::Header header(Imath::Box2i(Imath::V2i(-4, 0), Imath::V2i(9, 15)), dw);
    Imf::TiledRgbaOutputFile out(p.c_str(), header, Imf::WRITE_RGBA, 4, 3, Imf::ONE_LEVEL);
    out.setFrameBuffer(px.data() - (dw.min.x + std::ptrdiff_t(dw.min.y) * w), 1, w);
    out.writeTiles(0, out.numXTiles() - 1, 0, out.numYTiles() - 1);
  }
  const Image img = readExr(p);
  std::filesystem::remove(p);
  ASSERT_EQ(img.width(), w);
  ASSERT_EQ(img.height(), h);
  ASSERT_EQ(img.alpha().size(), std::size_t(w) * h);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      EXPECT_EQ(img.at(x, y), Vec3(float(x), float(y), 0.25f)) << x << ", " << y;
      EXPECT_EQ(img.alpha()[std::size_t(y) * w + x], 0.5f);
    }
}

// Issue 37: a procedural density whose value + rate·time leaves single precision rendered an
// empty medium (black, exit 0) or NaN; the time at which it overflows is refused, naming keys.
TEST(FiniteValues, DensityThatOverflowsAtTheSceneTimeNamesTheRate) {
  std::string m =
      sceneError({R"(medium.density={"type": "uniform", "value": 1, "rate": 1e38, "time": 100})"});
  EXPECT_TRUE(has(m,
                  "'medium.density.rate': 'value' + rate x time = 1e+40 at time 100 is "
                  "beyond single precision"))
      << m;
  m = sceneError({R"(medium.density={"type": "height", "bottom": 0, "top": 1, "rate": -1e38,
                     "time": 10})"});
  EXPECT_TRUE(has(m, "'medium.density.rate': 'bottom' + rate x time = -1e+39")) << m;
  m = sceneError({R"(medium.density={"type": "dusty-room", "wind": [0, 1e30, 0], "time": 1e10})"});
  EXPECT_TRUE(has(m,
                  "'medium.density.wind': wind x time = 1e+40 at time 1e+10 is beyond the "
                  "coordinate bound"))
      << m;
  // At a time where it stays finite, the same densities load.
  EXPECT_EQ(
      sceneError({R"(medium.density={"type": "uniform", "value": 1, "rate": 1e38, "time": 1})"}),
      "");
}
