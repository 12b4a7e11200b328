/// Did-you-mean (core/suggest.h) and the messages built on it: unknown registry names, choices
/// and keys suggest the likely one; an empty registry says to call initialize(); a scene path
/// that is not JSON says what the file is.

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>

#include "api/scatterlab.h"
#include "core/registry.h"
#include "core/suggest.h"

namespace scatterlab {
namespace {

std::string configErrorOf(const std::function<void()>& f) {
  try {
    f();
  } catch (const Error& e) {
    return e.what();
  }
  return "";
}

TEST(Suggest, EditDistanceCountsInsertionsDeletionsSubstitutionsAndSwaps) {
  EXPECT_EQ(editDistance("", ""), 0u);
  EXPECT_EQ(editDistance("abc", ""), 3u);
  EXPECT_EQ(editDistance("", "ab"), 2u);
  EXPECT_EQ(editDistance("gpu", "gpu"), 0u);
  EXPECT_EQ(editDistance("gpu", "cpu"), 1u);              // substitution
  EXPECT_EQ(editDistance("exat", "exact"), 1u);           // insertion
  EXPECT_EQ(editDistance("per-voxle", "per-voxel"), 1u);  // swap of neighbours
  EXPECT_EQ(editDistance("kitten", "sitting"), 3u);
  EXPECT_EQ(editDistance("GPU", "gpu"), 3u);  // case-sensitive
  EXPECT_EQ(editDistance("cuda", "cpu"), 3u);
}

TEST(Suggest, ClosestMatchOnlyForLikelyTypos) {
  const std::vector<std::string> backends{"cpu", "gpu", "auto"};
  EXPECT_EQ(closestMatch("GPU", backends), "gpu");  // case ignored
  EXPECT_EQ(closestMatch("cpuu", backends), "cpu");
  EXPECT_EQ(closestMatch("cuda", backends), "");  // 3 edits from every one
  EXPECT_EQ(closestMatch("", backends), "");
  EXPECT_EQ(closestMatch("gpu", backends), "");  // the word itself is not a suggestion
  const std::vector<std::string> methods{"adaptive", "exact", "gradient", "per-voxel", "rbf"};
  EXPECT_EQ(closestMatch("per-voxle", methods), "per-voxel");
  EXPECT_EQ(closestMatch("gradeint", methods), "gradient");
  EXPECT_EQ(closestMatch("pervoxel", methods), "per-voxel");
  EXPECT_EQ(closestMatch("nonsense", methods), "");
  EXPECT_EQ(didYouMean("exatc", methods), " (did you mean 'exact'?)");
  EXPECT_EQ(didYouMean("xyz", methods), "");
}

TEST(Suggest, RegistryNamesTheLikelyEntryAndAnEmptyOneSaysToInitialize) {
  Registry<int> r("density type");
  const std::string empty = configErrorOf([&] { r.get("gaussians", "medium.density.type"); });
  EXPECT_NE(empty.find("'medium.density.type': unknown density type 'gaussians'"),
            std::string::npos)
      << empty;
  EXPECT_NE(empty.find("call scatterlab::initialize()"), std::string::npos) << empty;
  EXPECT_EQ(empty.find("allowed: "), std::string::npos) << empty;  // no empty list
  r.add("gaussians", 1);
  r.add("uniform", 2);
  EXPECT_EQ(r.get("gaussians", "k"), 1);
  const std::string typo = configErrorOf([&] { r.get("gausians", "medium.density.type"); });
  EXPECT_EQ(typo,
            "'medium.density.type': unknown density type 'gausians' (did you mean 'gaussians'?); "
            "allowed: 'gaussians', 'uniform'");
}

TEST(Suggest, UnknownKeysAndChoicesSuggest) {
  Json doc = {{"widht", 3}, {"mode", "Linear"}};
  Params p(doc, "camera");
  p.integer("width", 10);
  EXPECT_EQ(configErrorOf([&] {
              p.choice("mode", {"linear", "filmic"});
            }),
            "'camera.mode': unknown value 'Linear' (did you mean 'linear'?); allowed: 'linear', "
            "'filmic'");
  const std::string e = configErrorOf([&] { p.finish(); });
  EXPECT_NE(e.find("unknown key 'camera.widht' (did you mean 'width'?)"), std::string::npos) << e;
}

TEST(Suggest, ASceneThatIsAVolumeOrAnImageSaysSo) {
  initialize();
  const std::filesystem::path dir = std::filesystem::path(::testing::TempDir()) / "suggest_files";
  std::filesystem::create_directories(dir);
  // The first bytes of an OpenVDB file (its magic number 0x56444220, then the version).
  const std::string vdb = (dir / "smoke.vdb").string();
  std::ofstream(vdb, std::ios::binary) << std::string("\x20\x42\x44\x56\0\0\0\0\xdc\0\0\0", 12);
  // Read as JSON (an experiment's config, a sweep file) it is named for what it is ...
  std::string e = configErrorOf([&] { readJsonFile(vdb); });
  EXPECT_NE(e.find("is an OpenVDB volume, not a scene (a JSON file)"), std::string::npos) << e;
  EXPECT_NE(e.find("{\"type\": \"vdb\", \"file\": \"smoke.vdb\"}"), std::string::npos) << e;
  EXPECT_EQ(e.find("malformed JSON"), std::string::npos) << e;
  // ... and as a scene it is a quick look (core/quick_look.h), whose reader names what is wrong
  // with this truncated file.
  e = configErrorOf([&] { loadScene(vdb); });
  EXPECT_NE(e.find("'" + vdb + "' is not a valid VDB file"), std::string::npos) << e;
  EXPECT_EQ(e.find("malformed JSON"), std::string::npos) << e;
  // By content whatever the name: an EXR named .json.
  const std::string exr = (dir / "image.json").string();
  std::ofstream(exr, std::ios::binary) << std::string("\x76\x2f\x31\x01\x02\0\0\0", 8);
  e = configErrorOf([&] { loadScene(exr); });
  EXPECT_NE(e.find("is an OpenEXR image, not a scene"), std::string::npos) << e;
  // A JSON file with a syntax error keeps the parser's message.
  const std::string bad = (dir / "bad.json").string();
  std::ofstream(bad) << "{\"camera\": ";
  e = configErrorOf([&] { loadScene(bad); });
  EXPECT_EQ(e.find("not a scene"), std::string::npos) << e;
  EXPECT_NE(e.find("bad.json"), std::string::npos) << e;
}

}  // namespace
}  // namespace scatterlab
