#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>

#include "core/atomic_file.h"
#include "core/error.h"
#include "core/grid.h"
#include "core/image.h"
#include "core/stages.h"

using namespace scatterlab;
namespace fs = std::filesystem;

TEST(Grid, CellCentresAndTrilinearReproduceLinearField) {
  DensityGrid g(Box{Vec3(-1, 0, 2), Vec3(1, 4, 3)}, IVec3(8, 5, 4));
  const auto f = [](const Vec3& p) { return 1.0f + 0.5f * p.x - 0.25f * p.y + 2.0f * p.z; };
  for (int k = 0; k < 4; ++k)
    for (int j = 0; j < 5; ++j)
      for (int i = 0; i < 8; ++i) g.at(i, j, k) = f(g.cellCenter(i, j, k));
  EXPECT_FLOAT_EQ(g.cellCenter(0, 0, 0).x, -1.0f + 0.125f);
  // Inside the hull of the centres, trilinear interpolation of a linear field is exact.
  for (const Vec3 p : {Vec3(0.1f, 2.2f, 2.5f), Vec3(-0.8f, 0.5f, 2.2f), Vec3(0.7f, 3.5f, 2.8f)})
    EXPECT_NEAR(g.sample(p), f(p), 1e-5);
  EXPECT_EQ(g.sample(Vec3(1.5f, 2, 2.5f)), 0.0f);  // outside the box
  // Between the box face and the first centre the value is clamped.
  EXPECT_NEAR(g.sample(Vec3(-0.99f, 2.2f, 2.5f)), f(Vec3(-0.875f, 2.2f, 2.5f)), 1e-5);
}

TEST(Grid, RefusesAbsurdSizes) {
  EXPECT_THROW(DensityGrid(Box{}, IVec3(0, 4, 4)), ConfigError);
  EXPECT_THROW(DensityGrid(Box{}, IVec3(4096, 4096, 4096)), LimitError);
}

TEST(Image, ExrRoundTripKeepsFloats) {
  Image img(7, 3);
  for (int y = 0; y < 3; ++y)
    for (int x = 0; x < 7; ++x) img.at(x, y) = Vec3(x * 0.125f, y * 1e3f, 1e-7f * (x + y));
  const std::string path = (fs::temp_directory_path() / "scatterlab_roundtrip.exr").string();
  writeExr(img, path);
  const Image back = readExr(path);
  ASSERT_EQ(back.width(), 7);
  ASSERT_EQ(back.height(), 3);
  for (size_t i = 0; i < img.pixels().size(); ++i) EXPECT_EQ(back.pixels()[i], img.pixels()[i]);
  fs::remove(path);
}

TEST(Image, PngIsWrittenAndToneMapIsSrgb) {
  EXPECT_FLOAT_EQ(toneMapSrgb(0.0f), 0.0f);
  EXPECT_FLOAT_EQ(toneMapSrgb(1.0f), 1.0f);
  EXPECT_NEAR(toneMapSrgb(0.5f), 0.7354f, 1e-4);
  EXPECT_NEAR(toneMapSrgb(0.25f, 1.0f), 0.7354f, 1e-4);  // one stop up
  Image img(4, 4);
  const std::string path = (fs::temp_directory_path() / "scatterlab_test.png").string();
  writePng(img, path);
  std::ifstream in(path, std::ios::binary);
  char sig[8];
  in.read(sig, 8);
  EXPECT_EQ(std::string(sig + 1, 3), "PNG");
  fs::remove(path);
}

TEST(Image, CompareMeasures) {
  Image a(2, 1), b(2, 1);
  b.at(0, 0) = Vec3(1, 0, 0);
  b.at(1, 0) = Vec3(0, 2, 0);
  a.at(0, 0) = Vec3(1, 0, 0);
  a.at(1, 0) = Vec3(0, 2.5f, 0);
  const ImageError e = compareImages(a, b);
  EXPECT_NEAR(e.relL2, 0.5 / std::sqrt(5.0), 1e-7);
  EXPECT_NEAR(e.relL1, 0.5 / 3.0, 1e-7);
  EXPECT_NEAR(e.maxAbs, 0.5, 1e-7);
  EXPECT_TRUE(std::isinf(compareImages(b, b).psnr));
  EXPECT_THROW(compareImages(a, Image(3, 1)), ConfigError);
}

TEST(Image, ReadErrorsNameTheFile) {
  const std::string dir = fs::temp_directory_path().string();
  try {
    readExr(dir);
    FAIL();
  } catch (const IoError& e) {
    EXPECT_NE(std::string(e.what()).find("is a directory"), std::string::npos);
  }
  const std::string bogus = (fs::temp_directory_path() / "scatterlab_bogus.exr").string();
  std::ofstream(bogus) << "not an exr";
  try {
    readExr(bogus);
    FAIL();
  } catch (const IoError& e) {
    EXPECT_NE(std::string(e.what()).find(bogus), std::string::npos);
  }
  fs::remove(bogus);
}

TEST(AtomicFile, FailedWriteLeavesNothing) {
  const fs::path path = fs::temp_directory_path() / "scatterlab_atomic.txt";
  fs::remove(path);
  EXPECT_THROW(writeAtomically(path.string(),
                               [](const std::string& tmp) {
                                 std::ofstream(tmp) << "partial";
                                 throw IoError("simulated failure");
                               }),
               IoError);
  EXPECT_FALSE(fs::exists(path));
  for (const auto& e : fs::directory_iterator(fs::temp_directory_path()))
    EXPECT_EQ(e.path().filename().string().find(".scatterlab_atomic.txt.tmp"), std::string::npos);
  EXPECT_THROW(checkWritablePath(fs::temp_directory_path().string()), IoError);
  EXPECT_THROW(checkWritablePath("/nonexistent-dir-xyz/out.exr"), IoError);
}

TEST(Grid, SingleVoxelAxesAreConstantAlongThem) {
  DensityGrid g(Box{Vec3(0), Vec3(1)}, IVec3(1, 3, 1));
  g.at(0, 0, 0) = 1.0f;
  g.at(0, 1, 0) = 2.0f;
  g.at(0, 2, 0) = 4.0f;
  EXPECT_FLOAT_EQ(g.sample(Vec3(0.1f, 0.5f, 0.9f)), 2.0f);
  EXPECT_FLOAT_EQ(g.sample(Vec3(0.7f, 0.5f + 1.0f / 6.0f, 0.2f)), 3.0f);
  EXPECT_FLOAT_EQ(g.sample(Vec3(0.5f, 0.99f, 0.5f)), 4.0f);
  EXPECT_FLOAT_EQ(g.sample(Vec3(0.5f, 0.01f, 0.5f)), 1.0f);
}

TEST(ToneCurve, PublishedValues) {
  // Linear clamps; ACES (Narkowicz) maps 1 to 2.54/3.16 and mid-grey 0.18 to 0.2669; Hable's
  // filmic normalised to white 11.2 maps 11.2 to 1 and 1 to 0.22066/0.72513 = 0.3043 (computed
  // by hand from A..F = 0.15, 0.5, 0.1, 0.2, 0.02, 0.3).
  EXPECT_FLOAT_EQ(toneCurve(0.5f, ToneCurve::Linear), 0.5f);
  EXPECT_FLOAT_EQ(toneCurve(3.0f, ToneCurve::Linear), 1.0f);
  EXPECT_NEAR(toneCurve(1.0f, ToneCurve::Aces), 2.54 / 3.16, 1e-6);
  EXPECT_NEAR(toneCurve(0.18f, ToneCurve::Aces), 0.26690, 1e-4);
  EXPECT_NEAR(toneCurve(11.2f, ToneCurve::Filmic), 1.0, 1e-6);
  EXPECT_NEAR(toneCurve(1.0f, ToneCurve::Filmic), 0.3043, 1e-3);
  for (ToneCurve c : {ToneCurve::Linear, ToneCurve::Filmic, ToneCurve::Aces}) {
    EXPECT_EQ(toneCurve(-1.0f, c), 0.0f);
    EXPECT_EQ(toneCurve(std::nanf(""), c), 0.0f);
    float prev = 0.0f;  // monotone, within [0, 1]
    for (float v = 0.01f; v < 50.0f; v *= 1.3f) {
      const float t = toneCurve(v, c);
      EXPECT_GE(t, prev);
      EXPECT_LE(t, 1.0f);
      prev = t;
    }
  }
  EXPECT_EQ(parseToneCurve("aces"), ToneCurve::Aces);
  try {
    parseToneCurve("reinhard");
    FAIL();
  } catch (const ConfigError& e) {
    EXPECT_NE(std::string(e.what()).find("allowed: linear, filmic, aces"), std::string::npos);
  }
}

TEST(Grid, OccupiedCellsCountAsTheVoxelByVoxelDefinition) {
  // occupiedCells / countOccupiedCells / occupiedVoxelsPerCell (parallel over layers of cells)
  // against the definition, voxel by voxel through voxelCells: a sparse pseudo-random field on
  // an odd grid, with cell grids coarser, equal and finer (empty cells) per axis.
  DensityGrid g(Box{Vec3(0), Vec3(1)}, IVec3(23, 17, 29));
  std::uint32_t x = 12345u;
  for (float& v : g.data()) {
    x = x * 1664525u + 1013904223u;
    v = (x >> 24) < 20 ? 1.0f : 0.0f;  // ~8 % occupied
  }
  for (const IVec3 dims : {IVec3(5, 4, 7), IVec3(23, 17, 29), IVec3(40, 3, 31), IVec3(1)}) {
    std::vector<int> want(std::size_t(dims.x) * dims.y * dims.z, 0);
    const std::vector<int> ci = voxelCells(23, dims.x), cj = voxelCells(17, dims.y),
                           ck = voxelCells(29, dims.z);
    for (int k = 0; k < 29; ++k)
      for (int j = 0; j < 17; ++j)
        for (int i = 0; i < 23; ++i)
          if (g.at(i, j, k) > 0.0f)
            ++want[std::size_t(ci[i]) +
                   std::size_t(dims.x) * (cj[j] + std::size_t(dims.y) * ck[k])];
    EXPECT_EQ(occupiedVoxelsPerCell(g, dims), want);
    std::vector<int> list;
    for (std::size_t c = 0; c < want.size(); ++c)
      if (want[c]) list.push_back(int(c));
    EXPECT_EQ(occupiedCells(g, dims), list);
    EXPECT_EQ(countOccupiedCells(g, dims), (long long)list.size());
    for (int c = 0; c < dims.z; ++c) {  // cellStarts: cell c holds the voxels that map to it
      const std::vector<int> first = cellStarts(29, dims.z);
      for (int k = first[c]; k < first[c + 1]; ++k) EXPECT_EQ(ck[k], c);
    }
  }
}
