// report.html (experiment/report_html.cpp): written by `experiment` and by `experiment merge`,
// its images decode (base64, inflate, byte planes, half floats) back to the EXRs the harness
// wrote within half precision, larger images are box-filtered with the originals linked, its
// table holds report.md's numbers, and bad inputs get one clear error. The page in a browser:
// tests/experiment/test_report_html_browser.py (ctest ReportHtml.*).

#include <gtest/gtest.h>
#include <unistd.h>
#include <zlib.h>

#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <map>

#include "api/scatterlab.h"
#include "experiment/experiment.h"
#include "support/scenes.h"

namespace scatterlab {
namespace {

namespace fs = std::filesystem;

// Half floats round to nearest: relative error at most 2^-11 = 4.88e-4 for normal values
// (|v| >= 2^-14). Measured 2026-11-26 over the images of this test: max relative error 4.83e-4
// (64×48), 4.76e-4 (box-filtered to 32×24); allowed ×1.5. Below 2^-14 halves are subnormal
// with a spacing of 2^-24: the absolute error is at most half of it (this scene has no such
// value: measured 0).
constexpr double kHalfRelTol = 7.2e-4;
constexpr double kHalfAbsTol = 2.98e-8;
// report.html of 3 images at 64×48 with no plots: measured 48646 bytes (2026-11-26): the page
// assets (~30 kB) plus ~6 kB per image. Allowed ×1.5.
constexpr std::uintmax_t kTinyPageBytes = 73000;

std::string readAll(const fs::path& p) {
  std::ifstream f(p, std::ios::binary);
  return std::string((std::istreambuf_iterator<char>(f)), {});
}

std::vector<unsigned char> unbase64(const std::string& s) {
  std::vector<unsigned char> out;
  unsigned v = 0;
  int bits = 0;
  for (char c : s) {
    int d;
    if (c >= 'A' && c <= 'Z')
      d = c - 'A';
    else if (c >= 'a' && c <= 'z')
      d = c - 'a' + 26;
    else if (c >= '0' && c <= '9')
      d = c - '0' + 52;
    else if (c == '+')
      d = 62;
    else if (c == '/')
      d = 63;
    else
      continue;  // '=' and white space
    v = v << 6 | unsigned(d);
    bits += 6;
    if (bits >= 8) {
      bits -= 8;
      out.push_back(static_cast<unsigned char>(v >> bits & 0xff));
    }
  }
  return out;
}

float halfToFloat(unsigned short h) {
  const int e = h >> 10 & 31, m = h & 1023;
  const float s = h & 0x8000 ? -1.0f : 1.0f;
  if (e == 0) return s * std::ldexp(float(m), -24);
  if (e == 31) return m ? NAN : s * INFINITY;
  return s * std::ldexp(1.0f + float(m) / 1024.0f, e - 15);
}

/// What a browser gets from report.html: the data JSON and, per image, its decoded RGB.
struct Page {
  Json data;
  std::map<std::string, std::string> blobs;  // data element id -> base64
  std::uintmax_t bytes = 0;

  explicit Page(const fs::path& file) {
    const std::string html = readAll(file);
    bytes = html.size();
    const std::string open = "<script type=\"application/json\" id=\"scatterlab-data\">";
    const std::size_t a = html.find(open);
    if (a == std::string::npos) throw std::runtime_error("no data element in " + file.string());
    const std::size_t b = html.find("</script>", a);
    data = Json::parse(html.substr(a + open.size(), b - a - open.size()));
    for (const Json& img : data["images"]) {
      const std::string id = img["data"].get<std::string>();
      const std::string tag = "id=\"" + id + "\">";
      const std::size_t s = html.find(tag);
      if (s == std::string::npos) throw std::runtime_error("no element " + id);
      blobs[id] = html.substr(s + tag.size(), html.find("</script>", s) - s - tag.size());
    }
  }

  /// The image's RGB as the page decodes it: inflate, low bytes then high bytes, halves.
  std::vector<float> pixels(const Json& img) const {
    const std::vector<unsigned char> packed = unbase64(blobs.at(img["data"].get<std::string>()));
    const std::size_t n = img["w"].get<std::size_t>() * img["h"].get<std::size_t>() * 3;
    std::vector<unsigned char> raw(2 * n + 1);
    uLongf len = uLongf(raw.size());
    EXPECT_EQ(uncompress(raw.data(), &len, packed.data(), uLong(packed.size())), Z_OK);
    EXPECT_EQ(len, 2 * n);
    std::vector<float> px(n);
    for (std::size_t i = 0; i < n; ++i)
      px[i] = halfToFloat(static_cast<unsigned short>(raw[i] | raw[n + i] << 8));
    return px;
  }
};

class ReportHtmlTest : public ::testing::Test {
 protected:
  void SetUp() override {
    initialize();
    dir = fs::temp_directory_path() /
          ("scatterlab_test_report_html_" +
           std::string(::testing::UnitTest::GetInstance()->current_test_info()->name()) + "_" +
           std::to_string(::getpid()));
    fs::remove_all(dir);
    fs::create_directories(dir);
    Json scene =
        testing::homogeneousBoxDoc(1.0f, 1.2f, 0.6f, Vec3(0.5f, 1.3f, 0.6f), 1.0f, 64, 48, 12);
    scene["render"] = {{"method", "per-voxel"}};
    std::ofstream(dir / "scene.json") << scene.dump(1);
  }
  void TearDown() override {
    if (!HasFailure()) fs::remove_all(dir);
  }

  /// The exact reference, per-voxel and gradient (grid samples): 2 runs, 1 reference image.
  fs::path config(const Json& extra = Json::object()) const {
    Json c = {{"title", "page"},
              {"scene", "scene.json"},
              {"references", {"exact"}},
              {"repetitions", 1},
              {"warmup", 0},
              {"methods",
               {"per-voxel",
                {{"name", "gradient"},
                 {"method", "gradient"},
                 {"set", {"render.sampler={\"type\": \"grid\"}", "render.sampler.count=64"}}}}}};
    c.update(extra);
    std::ofstream(dir / "exp.json") << c.dump(1);
    return dir / "exp.json";
  }

  ExperimentOptions options() const {
    ExperimentOptions opt;
    opt.progress = false;
    opt.plots = false;
    return opt;
  }

  /// Every image of `page` against its EXR (box-filtered by its factor), within half
  /// precision; the worst errors go to `rel` and `abs`.
  void expectImagesMatchExrs(const Page& page, const fs::path& out, double& rel, double& abs) {
    for (const Json& img : page.data["images"]) {
      const std::string exr = img["exr"].get<std::string>();
      const Image full = readExr((out / exr).string());
      const int f = img["factor"].get<int>(), w = img["w"].get<int>(), h = img["h"].get<int>();
      EXPECT_EQ(img["full_w"].get<int>(), full.width()) << exr;
      EXPECT_EQ(img["full_h"].get<int>(), full.height()) << exr;
      EXPECT_EQ(w, (full.width() + f - 1) / f) << exr;
      EXPECT_EQ(h, (full.height() + f - 1) / f) << exr;
      const std::vector<float> px = page.pixels(img);
      ASSERT_EQ(px.size(), std::size_t(w) * h * 3) << exr;
      double sum = 0;
      for (int y = 0; y < h; ++y)
        for (int x = 0; x < w; ++x) {
          // The box filter, computed here independently of the harness.
          Vec3 want(0.0f);
          int n = 0;
          for (int v = y * f; v < std::min(full.height(), (y + 1) * f); ++v)
            for (int u = x * f; u < std::min(full.width(), (x + 1) * f); ++u, ++n)
              want += full.at(u, v);
          want /= float(n);
          for (int c = 0; c < 3; ++c) {
            const double got = px[(std::size_t(y) * w + x) * 3 + c], v = want[c];
            sum += v;
            if (std::abs(v) >= std::ldexp(1.0, -14))
              rel = std::max(rel, std::abs(got - v) / std::abs(v));
            else
              abs = std::max(abs, std::abs(got - v));
          }
        }
      EXPECT_GT(sum, 0.0) << exr << ": an all-black image tests nothing";
    }
  }

  fs::path dir;
};

TEST_F(ReportHtmlTest, PageHoldsTheExrsAsHalfFloatsAndReportMdsNumbers) {
  // A title that would end the data element or open a comment if it were not escaped.
  const std::string title = "page </script><!-- & \"quoted\" <b>";
  const fs::path cfg = config({{"title", title}});
  const fs::path out = dir / "out";
  const ExperimentResult r = runExperiment(cfg.string(), out.string(), options());
  ASSERT_EQ(r.failed, 0);
  ASSERT_TRUE(fs::exists(out / "report.html"));
  const Page page(out / "report.html");
  EXPECT_EQ(page.data["title"], title);
  EXPECT_NE(
      readAll(out / "report.html")
          .find("<title>page &lt;/script&gt;&lt;!-- &amp; &quot;quoted&quot; &lt;b&gt;</title>"),
      std::string::npos);
  // One viewer: the reference then the two runs.
  ASSERT_EQ(page.data["groups"].size(), 1u);
  const Json& items = page.data["groups"][0]["items"];
  ASSERT_EQ(items.size(), 3u);
  EXPECT_EQ(items[0]["kind"], "reference");
  EXPECT_EQ(items[1]["run"], "per-voxel");
  EXPECT_EQ(items[2]["run"], "gradient");
  ASSERT_EQ(page.data["images"].size(), 3u);
  double rel = 0, abs = 0;
  expectImagesMatchExrs(page, out, rel, abs);
  std::printf("half precision: max relative error %.3g, max absolute (subnormal) %.3g\n", rel, abs);
  EXPECT_LE(rel, kHalfRelTol);
  EXPECT_LE(abs, kHalfAbsTol);
  for (const Json& img : page.data["images"]) {
    EXPECT_EQ(img["factor"], 1);
    EXPECT_TRUE(fs::exists(out / img["exr"].get<std::string>()));  // the original, linked
  }
  std::printf("report.html: %ju bytes\n", page.bytes);
  EXPECT_LE(page.bytes, kTinyPageBytes);
  // Deflated byte planes beat the raw halves, base64 included (3 × 64×48×6 bytes).
  EXPECT_LT(page.bytes, 3u * 64 * 48 * 6);

  // The table's error cells are report.md's (same formatting): each run's row has them.
  const std::string md = readAll(out / "report.md");
  const Json& cols = page.data["table"]["columns"];
  ASSERT_EQ(page.data["table"]["rows"].size(), 2u);
  for (const Json& row : page.data["table"]["rows"]) {
    const std::string id = row["run"].get<std::string>();
    const std::size_t line = md.find("| " + id + " |");
    ASSERT_NE(line, std::string::npos) << id;
    const std::string mdRow = md.substr(line, md.find('\n', line) - line);
    for (std::size_t c = 0; c < cols.size(); ++c) {
      const std::string col = cols[c].get<std::string>();
      if (col == "rel L2 vs exact" || col == "masked rel L2 (K px)" || col == "visibly wrong" ||
          col == "samples used" || col == "time (ms)") {
        // Built by appending: GCC 12 warns falsely (-Wrestrict) about " " + s + " |".
        std::string cell = " ";
        cell += row["cells"][c]["t"].get<std::string>();
        cell += " |";
        EXPECT_NE(mdRow.find(cell), std::string::npos)
            << col << " of " << id << ": " << cell << " not in " << mdRow;
      }
    }
    EXPECT_EQ(row["group"], 0);
  }
  // The overrides each run was rendered with, in the last column.
  ASSERT_EQ(cols.back(), "overrides (--set)");
  for (const Json& row : page.data["table"]["rows"]) {
    const std::string sets = row["cells"].back()["t"].get<std::string>();
    if (row["run"].get<std::string>().find("gradient") != std::string::npos) {
      EXPECT_NE(sets.find("render.sampler.count=64"), std::string::npos) << sets;
    }
  }
  // The viewers start as the PNGs look, and every image has its PNG for the overview.
  EXPECT_EQ(page.data["png_tone"], "linear");
  for (const Json& g : page.data["groups"])
    for (const Json& it : g["items"])
      EXPECT_TRUE(fs::exists(out / it["png"].get<std::string>())) << it["png"];
  EXPECT_EQ(page.data["machines"].size(), 1u);
  EXPECT_NE(page.data["machines"][0].get<std::string>().find("commit"), std::string::npos);

  // Larger than html_max_side: box-filtered (64×48 -> 32×24), the EXR linked at full size.
  config({{"title", title}, {"html_max_side", 32}});
  runExperiment(cfg.string(), out.string(), options());
  const Page small(out / "report.html");
  for (const Json& img : small.data["images"]) {
    EXPECT_EQ(img["factor"], 2);
    EXPECT_EQ(img["w"], 32);
    EXPECT_EQ(img["h"], 24);
  }
  double rel2 = 0, abs2 = 0;
  expectImagesMatchExrs(small, out, rel2, abs2);
  std::printf("box-filtered: max relative error %.3g, max absolute (subnormal) %.3g\n", rel2, abs2);
  EXPECT_LE(rel2, kHalfRelTol);
  EXPECT_LE(abs2, kHalfAbsTol);
  EXPECT_LT(small.bytes, page.bytes);
}

TEST_F(ReportHtmlTest, MergeWritesTheSamePageData) {
  const std::string cfg = config().string();
  ExperimentOptions opt = options();
  runExperiment(cfg, (dir / "whole").string(), opt);
  for (int k = 1; k <= 2; ++k) {
    opt.shardIndex = k;
    opt.shardCount = 2;
    runExperiment(cfg, (dir / ("shard" + std::to_string(k))).string(), opt);
    EXPECT_FALSE(fs::exists(dir / ("shard" + std::to_string(k)) / "report.html"));
  }
  opt.shardIndex = opt.shardCount = 0;
  mergeShards({(dir / "shard1").string(), (dir / "shard2").string()}, (dir / "merged").string(),
              opt);
  ASSERT_TRUE(fs::exists(dir / "merged" / "report.html"));
  const Page whole(dir / "whole" / "report.html"), merged(dir / "merged" / "report.html");
  // Deterministic renders: every image's data equal to the byte, under the same EXR name.
  std::map<std::string, std::string> a, b;
  for (const Json& img : whole.data["images"])
    a[img["exr"]] = whole.blobs.at(img["data"].get<std::string>());
  for (const Json& img : merged.data["images"])
    b[img["exr"]] = merged.blobs.at(img["data"].get<std::string>());
  EXPECT_EQ(a.size(), 3u);
  EXPECT_EQ(a, b);
  EXPECT_EQ(whole.data["groups"], merged.data["groups"]);
  double rel = 0, abs = 0;
  expectImagesMatchExrs(merged, dir / "merged", rel, abs);
  EXPECT_LE(rel, kHalfRelTol);
  EXPECT_LE(abs, kHalfAbsTol);
}

TEST_F(ReportHtmlTest, BadInputsGetOneClearError) {
  // html_max_side out of range: a ConfigError naming the key, before anything is rendered.
  for (const Json& bad : {Json(8), Json(-1), Json("big"), Json(1.5)}) {
    const fs::path cfg = config({{"html_max_side", bad}});
    try {
      runExperiment(cfg.string(), (dir / "bad").string(), options());
      ADD_FAILURE() << "html_max_side " << bad << " accepted";
    } catch (const ConfigError& e) {
      EXPECT_NE(std::string(e.what()).find("html_max_side"), std::string::npos) << e.what();
    }
    EXPECT_FALSE(fs::exists(dir / "bad" / "runs")) << bad;
  }
  // An image that cannot be read: the page is written without it and names it (page and log).
  const fs::path cfg = config();
  const fs::path out = dir / "out";
  runExperiment(cfg.string(), out.string(), options());
  std::ofstream(out / "images" / "gradient.exr") << "not an EXR";
  runExperiment(cfg.string(), out.string(), options());
  const Page page(out / "report.html");
  EXPECT_EQ(page.data["images"].size(), 2u);
  ASSERT_EQ(page.data["missing"].size(), 1u);
  const std::string missing = page.data["missing"][0].get<std::string>();
  EXPECT_EQ(missing.rfind("images/gradient.exr: ", 0), 0u) << missing;
  EXPECT_NE(readAll(out / "log.txt").find("report.html: image left out: images/gradient.exr"),
            std::string::npos);
  for (const Json& row : page.data["table"]["rows"])
    EXPECT_EQ(row.contains("group"), row["run"] != "gradient") << row["run"];
}

}  // namespace
}  // namespace scatterlab
