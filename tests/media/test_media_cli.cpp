// The `scatterlab fit` and `scatterlab info` commands on volumes: output, errors, no partial files.

#include <gtest/gtest.h>

#include <array>
#include <cstdio>
#include <filesystem>
#include <fstream>

#include "api/scatterlab.h"
#include "media/sog.h"
#include "media/temp_dir.h"
#include "media/vdb.h"
#include "support/scenes.h"

namespace scatterlab {
namespace {

using testing::kVdb;

struct CliRun {
  int code;
  std::string out;  // stdout and stderr together
};

CliRun run(const std::string& args) {
  const std::string cmd = std::string(SCATTERLAB_CLI) + " " + args + " 2>&1";
  FILE* p = popen(cmd.c_str(), "r");
  CliRun r{-1, ""};
  if (!p) return r;
  std::array<char, 4096> buf;
  size_t n;
  while ((n = fread(buf.data(), 1, buf.size(), p)) > 0) r.out.append(buf.data(), n);
  const int status = pclose(p);
  r.code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  return r;
}

TEST(MediaCli, InfoVdbListsGrids) {
  const CliRun r = run("info " + kVdb + "dragon_with_xform.vdb");
  ASSERT_EQ(r.code, 0) << r.out;
  EXPECT_NE(r.out.find("grid 'density': float, fog volume"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("[-70 1 -31]..[70 99 31] (141x99x63)"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("156161 voxels (20 active tiles"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("world box"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("values"), std::string::npos) << r.out;
}

TEST(MediaCli, FitWritesModelAndReportsErrors) {
  testing::TempDir tmp("cli_fit");
  const std::string out = tmp.file("dragon.sog");
  const CliRun r = run("fit " + kVdb + "dragon_with_xform.vdb -o " + out +
                       " --gaussians 32 --fit-voxels 4096 --sweeps 1");
  ASSERT_EQ(r.code, 0) << r.out;
  for (const char* key :
       {"gaussians", "hash entries", "bytes on disk", "rel. L2 D~ ", "rel. L2 D~ + F"})
    EXPECT_NE(r.out.find(key), std::string::npos) << key << "\n" << r.out;
  ASSERT_TRUE(std::filesystem::exists(out));
  EXPECT_NO_THROW(readSog(out));
  const CliRun info = run("info " + out);
  EXPECT_EQ(info.code, 0) << info.out;
  EXPECT_NE(info.out.find("residual hash"), std::string::npos) << info.out;
}

TEST(MediaCli, FitSequenceWritesEveryFrame) {
  testing::TempDir tmp("cli_fit");
  const std::string v = kVdb + "dragon_with_xform.vdb";
  const CliRun r = run("fit " + v + " " + v + " -o " + tmp.file("f_{frame}.sog") +
                       " --gaussians 16 --fit-voxels 4096 --sweeps 0");
  ASSERT_EQ(r.code, 0) << r.out;
  EXPECT_TRUE(std::filesystem::exists(tmp.file("f_0000.sog")));
  EXPECT_TRUE(std::filesystem::exists(tmp.file("f_0001.sog")));
  const CliRun bad = run("fit " + v + " " + v + " -o " + tmp.file("nopattern.sog"));
  EXPECT_NE(bad.code, 0);
  EXPECT_NE(bad.out.find("{frame}"), std::string::npos) << bad.out;
  EXPECT_FALSE(std::filesystem::exists(tmp.file("nopattern.sog")));
}

void expectFailure(const std::string& args, const std::string& needle, const std::string& out) {
  const CliRun r = run(args);
  EXPECT_NE(r.code, 0) << args << "\n" << r.out;
  EXPECT_NE(r.out.find(needle), std::string::npos) << args << "\n" << r.out;
  EXPECT_FALSE(std::filesystem::exists(out)) << out;
}

TEST(MediaCli, BadInputsFailWithMessageAndNoOutput) {
  testing::TempDir tmp("cli_bad");
  const std::string out = tmp.file("out.sog");
  expectFailure("fit /nonexistent/x.vdb -o " + out, "/nonexistent/x.vdb", out);
  const std::string text = tmp.file("text.vdb");
  std::ofstream(text) << "hello";
  expectFailure("fit " + text + " -o " + out, "not an OpenVDB file", out);
  std::ifstream in(kVdb + "smoke1.vdb", std::ios::binary);
  std::string all((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  const std::string cut = tmp.file("cut.vdb");
  std::ofstream(cut, std::ios::binary).write(all.data(), std::streamsize(all.size() / 2));
  expectFailure("fit " + cut + " -o " + out, "truncated", out);
  expectFailure("fit " + kVdb + "smoke1.vdb --grid temperature -o " + out, "'density' (float)",
                out);
  expectFailure("fit " + kVdb + "smoke1.vdb -o " + out + " --gaussians 0", "gaussians", out);
  expectFailure("fit " + kVdb + "smoke1.vdb -o /nonexistent-dir/out.sog", "/nonexistent-dir",
                "/nonexistent-dir/out.sog");
  // Foreign and truncated .sog files through `info`.
  const std::string foreign = tmp.file("foreign.sog");
  std::ofstream(foreign) << "not a model at all, just some text to fill the header........";
  expectFailure("info " + foreign, "not a valid .sog model", out);
  expectFailure("info " + cut, "truncated", out);
}

TEST(MediaCli, RenderExportsDensityAndRadianceVolumesAsVdb) {
  testing::TempDir tmp("exportvdb");
  const std::string scene = testing::kGlow;
  const std::string sets =
      " --set medium.resolution=16 --set camera.width=16 --set camera.height=12 -q";
  const CliRun r =
      run("render " + scene + " -o " + tmp.file("a.exr") + " --method per-voxel" +
          " --density-vdb " + tmp.file("d.vdb") + " --radiance-vdb " + tmp.file("s.vdb") + sets);
  ASSERT_EQ(r.code, 0) << r.out;
  const auto d = inspectVdb(tmp.file("d.vdb"));
  ASSERT_EQ(d.size(), 1u);
  EXPECT_EQ(d[0].name, "density");
  EXPECT_EQ(d[0].valueType, "float");
  const auto s = inspectVdb(tmp.file("s.vdb"));
  ASSERT_EQ(s.size(), 1u);
  EXPECT_EQ(s[0].name, "radiance");
  EXPECT_EQ(s[0].valueType, "vec3s");
  // The exported density is the volume the renderer built, voxel for voxel.
  initialize();
  const Scene sc = loadScene(scene, {"medium.resolution=16"});
  DensityGrid expected(sc.medium.bounds, sc.medium.resolution);
  sc.medium.density->build(expected);
  const DensityGrid back = loadVdbAsDense(tmp.file("d.vdb"), "density");
  ASSERT_EQ(back.dims(), expected.dims());
  for (std::size_t i = 0; i < back.size(); ++i)
    ASSERT_NEAR(back.data()[i], expected.data()[i], 1e-6f) << i;

  // `exact` builds no radiance volume: a clear error and no output at all.
  const CliRun bad = run("render " + scene + " -o " + tmp.file("b.exr") + " --method exact" +
                         " --radiance-vdb " + tmp.file("b.vdb") + sets);
  EXPECT_NE(bad.code, 0);
  EXPECT_NE(bad.out.find("--radiance-vdb"), std::string::npos) << bad.out;
  EXPECT_FALSE(std::filesystem::exists(tmp.file("b.exr")));
  EXPECT_FALSE(std::filesystem::exists(tmp.file("b.vdb")));
}

}  // namespace
}  // namespace scatterlab
