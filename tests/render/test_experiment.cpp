// The minimal experiment runner behind `scatterlab experiment` (experiment/experiment.h).

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>

#include "experiment/experiment.h"
#include "support/scenes.h"

namespace scatterlab {
namespace {

namespace fs = std::filesystem;

void writeJson(const fs::path& p, const Json& j) {
  std::ofstream(p) << j.dump(1);
}

TEST(Experiment, RendersReferencesAndRunsAndWritesTables) {
  const fs::path dir = fs::temp_directory_path() / "scatterlab_test_experiment";
  fs::remove_all(dir);
  fs::create_directories(dir);
  Json scene =
      testing::homogeneousBoxDoc(1.0f, 1.2f, 0.6f, Vec3(0.5f, 1.3f, 0.6f), 1.0f, 16, 12, 16);
  scene["render"] = {
      {"method", "exact"}};  // createMethod(scene, override) needs render.method today
  writeJson(dir / "scene.json", scene);
  writeJson(dir / "exp.json", {{"scene", "scene.json"},
                               {"references", {"per-voxel"}},
                               {"runs",
                                {{{"name", "g"},
                                  {"method", "gradient"},
                                  {"set", {"render.sampler={\"type\": \"grid\", \"count\": 64}"}},
                                  {"paper_rel_error", 0.043}}}}});
  initialize();
  const ExperimentResult r = runExperiment((dir / "exp.json").string(), (dir / "out").string());
  ASSERT_EQ(r.rows.size(), 2u);
  EXPECT_EQ(r.rows[0].errors[0].relL2, 0.0);
  EXPECT_GT(r.rows[1].errors[0].relL2, 0.0);
  EXPECT_LT(r.rows[1].errors[0].relL2, 0.1);
  EXPECT_EQ(*r.rows[1].stats.samples, 64);
  for (const char* f : {"per-voxel.exr", "per-voxel.png", "g.exr", "g.png", "side_by_side.png",
                        "results.csv", "results.md", "results.json"})
    EXPECT_TRUE(fs::exists(dir / "out" / f)) << f;
  std::ifstream csv(dir / "out" / "results.csv");
  std::string header, line;
  std::getline(csv, header);
  EXPECT_NE(header.find("rel_l2_vs_per-voxel"), std::string::npos);
  int rows = 0;
  while (std::getline(csv, line)) ++rows;
  EXPECT_EQ(rows, 2);

  // Unknown keys are errors naming them.
  writeJson(dir / "bad.json", {{"scene", "scene.json"},
                               {"references", {"per-voxel"}},
                               {"runs", {{{"name", "g"}, {"method", "gradient"}, {"colour", 1}}}}});
  try {
    runExperiment((dir / "bad.json").string(), (dir / "out2").string());
    ADD_FAILURE() << "expected ConfigError";
  } catch (const ConfigError& e) {
    EXPECT_NE(std::string(e.what()).find("colour"), std::string::npos) << e.what();
  }
  fs::remove_all(dir);
}

}  // namespace
}  // namespace scatterlab
