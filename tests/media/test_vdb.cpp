// OpenVDB input/output: the shared files load with the facts of their sidecars, round trips keep
// values, and every malformed input gives a clear typed error.

#include <gtest/gtest.h>

#include <openvdb/io/File.h>
#include <openvdb/openvdb.h>
#include <filesystem>
#include <fstream>

#include "api/scatterlab.h"
#include "media/procedural.h"
#include "media/temp_dir.h"
#include "media/vdb.h"
#include "support/scenes.h"

namespace scatterlab {
namespace {

using testing::kVdb;

const VdbGridInfo& only(const std::vector<VdbGridInfo>& v) {
  EXPECT_EQ(v.size(), 1u);
  return v.front();
}

TEST(Vdb, Smoke1MatchesSidecar) {
  const auto infos = inspectVdb(kVdb + "smoke1.vdb");
  const VdbGridInfo& g = only(infos);
  EXPECT_EQ(g.name, "density");
  EXPECT_EQ(g.valueType, "float");
  EXPECT_EQ(g.gridClass, "fog volume");
  EXPECT_EQ(g.indexMin, IVec3(1, 2, 1));
  EXPECT_EQ(g.indexMax, IVec3(111, 223, 112));
  EXPECT_EQ(g.activeVoxels, 1049275u);
  EXPECT_EQ(g.activeTiles, 0u);
  EXPECT_NEAR(g.voxelSize.x, 0.47619, 1e-5);
  EXPECT_NEAR(g.valueMin, 1.0e-5, 1e-5);
  EXPECT_NEAR(g.valueMax, 5.715, 1e-3);  // half-float storage, values above 1
  // Voxel-centre box [-33.57,-12.14,-25.95]..[18.81,93.10,26.90], cells half a voxel wider.
  const float h = 0.5f * 0.47619f;
  EXPECT_NEAR(g.worldBounds.min.x, -33.57f - h, 0.01f);
  EXPECT_NEAR(g.worldBounds.min.y, -12.14f - h, 0.01f);
  EXPECT_NEAR(g.worldBounds.max.y, 93.10f + h, 0.01f);
  EXPECT_NEAR(g.worldBounds.max.z, 26.90f + h, 0.01f);
}

TEST(Vdb, CloudMatchesSidecarIncludingActiveTiles) {
  const VdbGridInfo g = only(inspectVdb(kVdb + "wdas_cloud_sixteenth.vdb"));
  EXPECT_EQ(g.name, "density");
  EXPECT_EQ(g.indexMin, IVec3(-66, -21, -90));
  EXPECT_EQ(g.indexMax, IVec3(59, 64, 63));
  EXPECT_EQ(g.activeVoxels, 415642u);
  EXPECT_EQ(g.activeTiles, 130u);
  EXPECT_NEAR(g.valueMin, 0.0, 1e-6);
  EXPECT_NEAR(g.valueMax, 1.0, 1e-6);
  // Sidecar (voxel centres) ~[-220,-70,-300]-[196.7,213.3,210]; cells half a voxel wider.
  const float h = 0.5f * 3.33333f;
  EXPECT_NEAR(g.worldBounds.min.x, -220.0f - h, 0.1f);
  EXPECT_NEAR(g.worldBounds.max.y, 213.3f + h, 0.1f);
  EXPECT_NEAR(g.worldBounds.max.z, 210.0f + h, 0.1f);

  // The tile interior must read as density, not as background: the grid's mean over active
  // values is 0.454, so the centre of the cloud must be dense.
  const auto d = VdbDensity::load(kVdb + "wdas_cloud_sixteenth.vdb", "density");
  DensityGrid grid(*d->naturalBounds(), d->nativeDims(64 * 64 * 64));
  d->build(grid);
  double sum = 0;
  size_t nonzero = 0;
  for (float v : grid.data()) {
    sum += v;
    nonzero += v > 0;
  }
  EXPECT_GT(nonzero, grid.size() / 10);
  EXPECT_GT(sum / double(nonzero), 0.3);
}

TEST(Vdb, DragonRotatedTransformGivesRotatedWorldBounds) {
  const auto d = VdbDensity::load(kVdb + "dragon_with_xform.vdb", "density");
  const VdbGridInfo& g = d->info();
  EXPECT_EQ(g.indexMin, IVec3(-70, 1, -31));
  EXPECT_EQ(g.indexMax, IVec3(70, 99, 31));
  EXPECT_EQ(g.activeVoxels, 156161u);
  EXPECT_EQ(g.activeTiles, 20u);
  EXPECT_NEAR(g.voxelSize.x, 0.12, 1e-3);
  EXPECT_NEAR(g.valueMax, 1.0, 1e-6);
  // Sidecar: world AABB of the rotated index box ~[-13.40,-5.23,-6.68]-[7.52,15.00,11.38].
  // (The sidecar's box is that of the voxel cells or the centres: allow half a voxel.)
  const Box b = *d->naturalBounds();
  const Vec3 lo(-13.40f, -5.23f, -6.68f), hi(7.52f, 15.00f, 11.38f);
  for (int a = 0; a < 3; ++a) {
    EXPECT_NEAR(b.min[a], lo[a], 0.12f) << a;
    EXPECT_NEAR(b.max[a], hi[a], 0.12f) << a;
  }
  // An axis-aligned box would be far smaller than the rotated one in x (index x spans 141
  // voxels of 0.12 = 16.9 world units, the rotated box 20.9).
  EXPECT_GT(b.extent().x, 20.0f);
  // Density in the box: the transform is honoured, so the sampled volume is not empty.
  DensityGrid grid(b, IVec3(48));
  d->build(grid);
  float mx = 0;
  for (float v : grid.data()) mx = std::max(mx, v);
  EXPECT_GT(mx, 0.9f);
}

TEST(Vdb, EvalEqualsBuildAtCellCentres) {
  const auto d = VdbDensity::load(kVdb + "dragon_with_xform.vdb", "density");
  DensityGrid grid(*d->naturalBounds(), IVec3(24, 20, 18));
  d->build(grid);
  for (int k = 0; k < 18; k += 3)
    for (int j = 0; j < 20; j += 3)
      for (int i = 0; i < 24; i += 3)
        EXPECT_FLOAT_EQ(grid.at(i, j, k), d->eval(grid.cellCenter(i, j, k)));
}

TEST(Vdb, Smoke1NativeDenseMatchesVoxels) {
  const auto d = VdbDensity::load(kVdb + "smoke1.vdb", "density");
  EXPECT_EQ(d->nativeDims(), IVec3(111, 222, 112));
  DensityGrid grid(*d->naturalBounds(), d->nativeDims());
  d->build(grid);
  // Cell (i, j, k) is voxel (i+1, j+2, k+1) of the file (index box starts at [1,2,1]); the
  // sampler lands on voxel centres up to float rounding of the positions.
  ensureOpenVdbInitialized();
  openvdb::io::File f(kVdb + "smoke1.vdb");
  f.open(false);
  auto vdb = openvdb::gridPtrCast<openvdb::FloatGrid>(f.readGrid("density"));
  auto acc = vdb->getConstAccessor();
  double sum = 0, maxErr = 0;
  float mx = 0;
  for (int k = 0; k < 112; ++k)
    for (int j = 0; j < 222; ++j)
      for (int i = 0; i < 111; ++i) {
        const float v = acc.getValue(openvdb::Coord(i + 1, j + 2, k + 1));
        maxErr = std::max(maxErr, double(std::abs(grid.at(i, j, k) - v)));
        sum += grid.at(i, j, k);
        mx = std::max(mx, grid.at(i, j, k));
      }
  EXPECT_LT(maxErr, 1e-3);
  EXPECT_NEAR(mx, 5.715f, 2e-3f);
  EXPECT_NEAR(sum / 1049275.0, 0.163, 2e-3);  // sidecar: mean of active voxels
  // peak(): the largest active value, the maximum of the voxels read back here.
  ASSERT_TRUE(d->peak().has_value());
  EXPECT_FLOAT_EQ(*d->peak(), mx);
}

TEST(Vdb, DenseToVdbToDenseRoundTrip) {
  testing::TempDir tmp("vdb_roundtrip");
  GaussianDensity blobs(
      {{Vec3(0.3f, 0.5f, 0.5f), 0.15f, 1.5f}, {Vec3(0.7f, 0.4f, 0.6f), 0.1f, 0.7f}});
  const Box box{Vec3(0, 0, 0.2f), Vec3(1.2f, 1, 1)};
  DensityGrid g(box, IVec3(20, 12, 9));
  blobs.build(g);
  const std::string path = tmp.file("blobs.vdb");
  writeVdb(path, g);
  const auto d = VdbDensity::load(path, "density");
  const Box b = *d->naturalBounds();
  for (int a = 0; a < 3; ++a) {
    // The whole box comes back from the metadata, though the zero border is inactive.
    EXPECT_FLOAT_EQ(b.min[a], box.min[a]);
    EXPECT_FLOAT_EQ(b.max[a], box.max[a]);
  }
  DensityGrid back(box, g.dims());
  d->build(back);
  for (size_t i = 0; i < g.size(); ++i) ASSERT_NEAR(back.data()[i], g.data()[i], 1e-5f) << i;
}

// The issue-15 round trip: a render's density exported to VDB (zero margins included) and
// rendered again from the file, with no medium.bounds, gives the same image; sigma_t, albedo
// and units ride along as grid metadata.
TEST(Vdb, ExportThenRerenderEqualsOriginal) {
  testing::TempDir tmp("vdb_rerender");
  Json doc = testing::homogeneousBoxDoc(1.0f, 4.0f, 0.6f, Vec3(0.5f, 1.3f, 0.5f), 3.0f, 40, 30, 32);
  doc["medium"]["density"] = {
      {"type", "gaussians"},
      {"blobs", Json::array({{{"center", {0.45, 0.5, 0.5}}, {"radius", 0.15}, {"weight", 1.0}},
                             {{"center", {0.6, 0.55, 0.45}}, {"radius", 0.1}, {"weight", 0.7}}})}};
  const Scene s = testing::sceneFromJson(doc);
  const RenderResult original = createMethod(s, "exact", "cpu")->render(s, nullptr);
  ASSERT_TRUE(original.density);
  const std::string path = tmp.file("density.vdb");
  writeVdb(path, *original.density, "density", {4.0f, 0.6f, "metres"});

  Json again = doc;
  again["medium"].erase("bounds");
  again["medium"]["density"] = {{"type", "vdb"}, {"file", path}};
  const Scene s2 = testing::sceneFromJson(again);
  for (int a = 0; a < 3; ++a) {
    EXPECT_FLOAT_EQ(s2.medium.bounds.min[a], 0.0f);
    EXPECT_FLOAT_EQ(s2.medium.bounds.max[a], 1.0f);
  }
  const RenderResult back = createMethod(s2, "exact", "cpu")->render(s2, nullptr);
  // Measured 0 (same cell centres, trilinear at the nodes); bound 0.1 % from the issue.
  EXPECT_LT(compareImages(back.image, original.image).relL2, 1e-3);

  ensureOpenVdbInitialized();
  openvdb::io::File f(path);
  f.open(false);
  const openvdb::GridBase::Ptr g = f.readGrid("density");
  EXPECT_FLOAT_EQ(g->metaValue<float>("sigma_t"), 4.0f);
  EXPECT_FLOAT_EQ(g->metaValue<float>("albedo"), 0.6f);
  EXPECT_EQ(g->metaValue<std::string>("units"), "metres");
  EXPECT_EQ(g->metaValue<openvdb::Vec3d>(kVdbBoundsMax), openvdb::Vec3d(1, 1, 1));
}

TEST(Vdb, VdbToDenseToVdbRoundTripKeepsSmokeValues) {
  testing::TempDir tmp("vdb_roundtrip2");
  const DensityGrid dense = loadVdbAsDense(kVdb + "smoke1.vdb", "density");
  const std::string path = tmp.file("smoke_again.vdb");
  writeVdb(path, dense);
  const VdbGridInfo again = only(inspectVdb(path));
  // Float rounding of the sample positions leaves tiny (~1e-5 relative) bleed into some
  // neighbours of active voxels, so the count can only grow.
  EXPECT_GE(again.activeVoxels, 1049275u);
  EXPECT_NEAR(again.valueMax, 5.715, 2e-3);
  // Same values at the same world points, original against written file.
  const auto a = VdbDensity::load(kVdb + "smoke1.vdb", "density");
  const auto b = VdbDensity::load(path, "density");
  const Box box = *a->naturalBounds();
  const Box box2 = *b->naturalBounds();
  for (int ax = 0; ax < 3; ++ax) {
    EXPECT_NEAR(box.min[ax], box2.min[ax], 1e-3f);
    EXPECT_NEAR(box.max[ax], box2.max[ax], 1e-3f);
  }
  for (int s = 0; s < 2000; ++s) {
    const Vec3 t(float((s * 37) % 101) / 101, float((s * 53) % 103) / 103,
                 float((s * 71) % 107) / 107);
    const Vec3 p = box.min + t * box.extent();
    ASSERT_NEAR(a->eval(p), b->eval(p), 1e-4f) << s;
  }
}

TEST(Vdb, RadianceGridWritesVec3Grid) {
  testing::TempDir tmp("vdb_radiance");
  RadianceGrid r(Box{Vec3(0), Vec3(2)}, IVec3(4, 5, 6), Vec3(0));
  r.at(1, 2, 3) = Vec3(1, 2, 3);
  r.at(0, 0, 0) = Vec3(0.5f, 0, 0);
  const std::string path = tmp.file("rad.vdb");
  writeVdb(path, r);
  const VdbGridInfo g = only(inspectVdb(path));
  EXPECT_EQ(g.name, "radiance");
  EXPECT_EQ(g.valueType, "vec3s");
  EXPECT_EQ(g.activeVoxels, 2u);
  EXPECT_NEAR(g.valueMax, std::sqrt(14.0), 1e-5);
  // Voxel (1,2,3) sits at the centre of cell (1,2,3).
  ensureOpenVdbInitialized();
  openvdb::io::File f(path);
  f.open(false);
  auto grid = openvdb::gridPtrCast<openvdb::Vec3SGrid>(f.readGrid("radiance"));
  const openvdb::Vec3d w = grid->transform().indexToWorld(openvdb::Vec3d(1, 2, 3));
  const Vec3 c = r.cellCenter(1, 2, 3);
  EXPECT_NEAR(w.x(), c.x, 1e-6);
  EXPECT_NEAR(w.y(), c.y, 1e-6);
  EXPECT_NEAR(w.z(), c.z, 1e-6);
  EXPECT_EQ(grid->tree().getValue(openvdb::Coord(1, 2, 3)), openvdb::Vec3s(1, 2, 3));
}

TEST(Vdb, SceneWithVdbDefaultsBoxToGridBounds) {
  const Json doc = {
      {"medium",
       {{"density", {{"type", "vdb"}, {"file", kVdb + "smoke1.vdb"}, {"grid", "density"}}},
        {"resolution", 16}}},
      {"lights", Json::array({{{"type", "point"}, {"position", {0, 50, -60}}, {"intensity", 1}}})},
      {"camera", {{"position", {0, 40, -150}}, {"look_at", {0, 40, 0}}}}};
  const Scene s = testing::sceneFromJson(doc);
  EXPECT_NEAR(s.medium.bounds.min.y, -12.14f - 0.238f, 0.01f);
  EXPECT_NEAR(s.medium.bounds.max.y, 93.10f + 0.238f, 0.01f);
}

// ---- bad input ----

template <class E>
std::string messageOf(const std::function<void()>& f) {
  try {
    f();
  } catch (const E& e) {
    return e.what();
  } catch (const std::exception& e) {
    ADD_FAILURE() << "wrong exception type: " << e.what();
    return "";
  }
  ADD_FAILURE() << "no exception";
  return "";
}

TEST(VdbErrors, MissingFile) {
  const std::string m =
      messageOf<IoError>([] { VdbDensity::load("/nonexistent/none.vdb", "density"); });
  EXPECT_NE(m.find("/nonexistent/none.vdb"), std::string::npos) << m;
}

TEST(VdbErrors, NotAVdb) {
  testing::TempDir tmp("vdb_err");
  const std::string p = tmp.file("text.vdb");
  std::ofstream(p) << "this is not a volume\n";
  const std::string m = messageOf<IoError>([&] { VdbDensity::load(p, "density"); });
  EXPECT_NE(m.find("not an OpenVDB file"), std::string::npos) << m;
  const std::string m2 = messageOf<IoError>([&] { inspectVdb(p); });
  EXPECT_NE(m2.find("not an OpenVDB file"), std::string::npos) << m2;
}

TEST(VdbErrors, TruncatedVdb) {
  testing::TempDir tmp("vdb_err");
  std::ifstream in(kVdb + "smoke1.vdb", std::ios::binary);
  const std::string all((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  for (size_t keep : {size_t(12), size_t(300), all.size() / 2, all.size() - 100}) {
    const std::string p = tmp.file("cut" + std::to_string(keep) + ".vdb");
    std::ofstream(p, std::ios::binary).write(all.data(), std::streamsize(keep));
    const std::string m = messageOf<IoError>([&] { VdbDensity::load(p, "density"); });
    EXPECT_NE(m.find(p), std::string::npos) << keep << ": " << m;
  }
}

TEST(VdbErrors, MissingGridListsGrids) {
  const std::string m =
      messageOf<ConfigError>([&] { VdbDensity::load(kVdb + "smoke1.vdb", "temperature"); });
  EXPECT_NE(m.find("temperature"), std::string::npos) << m;
  EXPECT_NE(m.find("'density' (float)"), std::string::npos) << m;
}

TEST(VdbErrors, WrongGridType) {
  testing::TempDir tmp("vdb_err");
  RadianceGrid r(Box{Vec3(0), Vec3(1)}, IVec3(4), Vec3(1));
  const std::string p = tmp.file("vel.vdb");
  writeVdb(p, r, "density");
  const std::string m = messageOf<ConfigError>([&] { VdbDensity::load(p, "density"); });
  EXPECT_NE(m.find("vec3s"), std::string::npos) << m;
  EXPECT_NE(m.find("'float'"), std::string::npos) << m;
}

TEST(VdbErrors, NonAffineTransform) {
  testing::TempDir tmp("vdb_err");
  ensureOpenVdbInitialized();
  auto g = openvdb::FloatGrid::create(0.0f);
  g->setName("density");
  g->tree().setValue(openvdb::Coord(1, 1, 1), 1.0f);
  openvdb::BBoxd frame(openvdb::Vec3d(0), openvdb::Vec3d(10));
  g->setTransform(openvdb::math::Transform::createFrustumTransform(frame, 0.5, 2.0, 1.0));
  const std::string p = tmp.file("frustum.vdb");
  openvdb::io::File f(p);
  f.write({g});
  f.close();
  const std::string m = messageOf<ConfigError>([&] { VdbDensity::load(p, "density"); });
  EXPECT_NE(m.find("not affine"), std::string::npos) << m;
}

TEST(VdbErrors, SceneKeyNamedInGridError) {
  const Json doc = {
      {"medium", {{"density", {{"type", "vdb"}, {"file", kVdb + "smoke1.vdb"}, {"grid", "nope"}}}}},
      {"lights", Json::array({{{"type", "point"}, {"position", {0, 0, 0}}, {"intensity", 1}}})},
      {"camera", {{"position", {0, 0, -5}}, {"look_at", {0, 0, 0}}}}};
  const std::string m = messageOf<ConfigError>([&] { testing::sceneFromJson(doc); });
  EXPECT_NE(m.find("medium.density.grid"), std::string::npos) << m;
  EXPECT_NE(m.find("'density'"), std::string::npos) << m;
}

TEST(VdbErrors, WriteLeavesNoPartialFile) {
  DensityGrid g(Box{}, IVec3(2));
  EXPECT_THROW(writeVdb("/nonexistent-dir/x.vdb", g), IoError);
}

}  // namespace
}  // namespace scatterlab
