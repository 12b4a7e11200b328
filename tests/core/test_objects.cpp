/// Scene objects as parsed (core/objects.h): mesh transforms, ray hits and occlusion queries.

#include <gtest/gtest.h>

#include <optional>

#include <fstream>

#include "media/temp_dir.h"
#include "support/scenes.h"

using namespace scatterlab;

namespace {

Json baseDoc() {
  return scatterlab::testing::homogeneousBoxDoc(1.0f, 1.0f, 1.0f, Vec3(0.5f, 2.0f, 0.5f), 1.0f, 4,
                                                4, 4);
}

void expectVec(const Vec3& a, const Vec3& b) {
  for (int i = 0; i < 3; ++i) EXPECT_NEAR(a[i], b[i], 1e-5f) << i;
}

}  // namespace

TEST(SceneObjects, MeshTransformIsTranslateRzRyRxScale) {
  scatterlab::testing::TempDir dir("objects_xf");
  std::ofstream(dir.file("t.obj")) << "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n";
  Json doc = baseDoc();
  // x' = (1,2,3) + Rz(90°)·(2x): (1,0,0) -> (1,4,3), (0,1,0) -> (-1,2,3), (0,0,0) -> (1,2,3).
  doc["objects"] = Json::array(
      {{{"type", "mesh"},
        {"file", dir.file("t.obj")},
        {"transform", {{"translate", {1, 2, 3}}, {"rotate_deg", {0, 0, 90}}, {"scale", 2}}}},
       // Rx first, then Ry: (1,0,0) -> (0,0,-1), (0,1,0) -> (1,0,0).
       {{"type", "mesh"},
        {"file", dir.file("t.obj")},
        {"transform", {{"rotate_deg", {90, 90, 0}}}}},
       // Per-axis scale.
       {{"type", "mesh"}, {"file", dir.file("t.obj")}, {"transform", {{"scale", {3, 0.5, 1}}}}}});
  const Scene s = scatterlab::testing::sceneFromJson(doc);
  ASSERT_TRUE(s.objects);
  const auto& o = s.objects->objects();
  ASSERT_EQ(o.size(), 3u);
  expectVec(o[0].bounds.min, Vec3(-1, 2, 3));
  expectVec(o[0].bounds.max, Vec3(1, 4, 3));
  expectVec(o[1].bounds.min, Vec3(0, 0, -1));
  expectVec(o[1].bounds.max, Vec3(1, 0, 0));
  expectVec(o[2].bounds.max, Vec3(3, 0.5, 0));
  EXPECT_EQ(o[0].triangles, 1);
  EXPECT_EQ(s.objects->triangles(), 3);
}

TEST(SceneObjects, HitsAndOcclusion) {
  Json doc = baseDoc();
  doc["objects"] = Json::array(
      {{{"type", "sphere"}, {"center", {0, 0, 5}}, {"radius", 1}, {"albedo", {0.1, 0.2, 0.3}}},
       {{"type", "box"}, {"min", {-1, -1, 10}}, {"max", {1, 1, 11}}, {"albedo", 0.5}}});
  const Scene s = scatterlab::testing::sceneFromJson(doc);
  SurfaceHit h;
  // Along +z from the origin: the sphere's front at t = 4, normal facing back (-z).
  ASSERT_TRUE(s.objects->intersect(Ray{Vec3(0), Vec3(0, 0, 1)}, 0.0f, kInfinity, h));
  EXPECT_NEAR(h.t, 4.0f, 1e-5f);
  expectVec(h.normal, Vec3(0, 0, -1));
  expectVec(h.albedo, Vec3(0.1f, 0.2f, 0.3f));
  EXPECT_EQ(h.object, 0);
  // From inside the sphere: its far side at t = 1, the normal turned towards the origin.
  ASSERT_TRUE(s.objects->intersect(Ray{Vec3(0, 0, 5), Vec3(0, 0, 1)}, 0.0f, kInfinity, h));
  EXPECT_NEAR(h.t, 1.0f, 1e-5f);
  expectVec(h.normal, Vec3(0, 0, -1));
  // Beyond the sphere: the box's face at z = 10.
  ASSERT_TRUE(s.objects->intersect(Ray{Vec3(0, 0, 7), Vec3(0, 0, 1)}, 0.0f, kInfinity, h));
  EXPECT_NEAR(h.t, 3.0f, 1e-5f);
  EXPECT_EQ(h.object, 1);
  // tmax before the first hit: nothing.
  EXPECT_FALSE(s.objects->intersect(Ray{Vec3(0), Vec3(0, 0, 1)}, 0.0f, 3.9f, h));
  EXPECT_TRUE(s.objects->occluded(Vec3(0), Vec3(0, 0, 1), 0.0f, 4.1f));
  EXPECT_FALSE(s.objects->occluded(Vec3(0), Vec3(0, 0, 1), 0.0f, 3.9f));
  EXPECT_TRUE(s.objects->occluded(Vec3(0, 0, 7), Vec3(0, 0, 1), 0.0f, kInfinity));
  EXPECT_FALSE(s.objects->occluded(Vec3(0), Vec3(1, 0, 0), 0.0f, kInfinity));
}

// Issue 37: a .mtl Kd outside [0, 1] (or not a number) was clamped silently; it is an error
// naming the material, unless the scene gives the albedo itself.
TEST(SceneObjects, MaterialAlbedoOutsideTheUnitRangeIsAnError) {
  scatterlab::testing::TempDir dir("objects_kd");
  std::ofstream(dir.file("t.obj"))
      << "mtllib t.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nusemtl hot\nf 1 2 3\n";
  // The IoError of a mesh whose material has `kd` ("" when it loads), with the scene's albedo
  // `albedo` when given.
  const auto kdError = [&](const char* kd, std::optional<double> albedo) -> std::string {
    std::ofstream(dir.file("t.mtl")) << "newmtl hot\nKd " << kd << "\n";
    Json doc = baseDoc();
    doc["objects"] = Json::array({{{"type", "mesh"}, {"file", dir.file("t.obj")}}});
    if (albedo) doc["objects"][0]["albedo"] = *albedo;
    try {
      scatterlab::testing::sceneFromJson(doc);
    } catch (const IoError& e) {
      return e.what();
    }
    return "";
  };
  for (const char* kd : {"1.5 0.2 0.2", "-0.1 0.2 0.2"}) {
    const std::string m = kdError(kd, std::nullopt);
    EXPECT_NE(m.find("'objects[0].file': material 'hot' of '"), std::string::npos) << kd << m;
    EXPECT_NE(m.find("outside [0, 1] per channel (an albedo); fix the .mtl or give "
                     "'objects[0].albedo'"),
              std::string::npos)
        << m;
    EXPECT_EQ(kdError(kd, 0.5), "") << kd;  // the scene's albedo: the Kd is not used
  }
  // Not numbers at all (tinyobjloader read them as 0): an error naming the line, albedo or not.
  for (const char* kd : {"inf 0 0", "nan 0.5 0.5", "0.5 0.5"}) {
    const std::string m = kdError(kd, std::nullopt);
    EXPECT_NE(m.find("t.mtl' line 2: 'Kd "), std::string::npos) << kd << m;
    EXPECT_NE(m.find("' is not Kd and three finite numbers"), std::string::npos) << m;
  }
}

TEST(SceneObjects, ShapesHandTheSurfacesToRasterisers) {
  // shapes() (the GPU's input) holds what the BVH was built from, by object index: a sphere's
  // centre and radius, a box's 8 corners and 12 triangles, a mesh's transformed vertices and
  // per-triangle albedo from its .mtl.
  scatterlab::testing::TempDir dir("objects_shapes");
  std::ofstream(dir.file("t.mtl")) << "newmtl red\nKd 0.9 0.1 0.1\n";
  std::ofstream(dir.file("t.obj"))
      << "mtllib t.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nv 1 1 0\nusemtl red\nf 1 2 3\nf 2 4 3\n";
  Json doc = baseDoc();
  doc["objects"] = Json::array(
      {{{"type", "sphere"}, {"center", {1, 2, 3}}, {"radius", 0.5}, {"albedo", 0.25}},
       {{"type", "box"}, {"min", {0, 0, 0}}, {"max", {1, 2, 3}}},
       {{"type", "mesh"}, {"file", dir.file("t.obj")}, {"transform", {{"translate", {0, 0, 5}}}}}});
  const Scene s = scatterlab::testing::sceneFromJson(doc);
  const auto& shapes = s.objects->shapes();
  ASSERT_EQ(shapes.size(), 3u);
  EXPECT_EQ(shapes[0].kind, ObjectShape::Kind::Sphere);
  expectVec(shapes[0].center, Vec3(1, 2, 3));
  EXPECT_EQ(shapes[0].radius, 0.5f);
  expectVec(shapes[0].albedo.at(0), Vec3(0.25f));
  EXPECT_EQ(shapes[1].kind, ObjectShape::Kind::Triangles);
  EXPECT_EQ(shapes[1].vertices.size(), 8u);
  EXPECT_EQ(shapes[1].triangles.size(), 12u);
  expectVec(shapes[1].albedo.at(0), Vec3(0.8f));  // the default
  expectVec(shapes[1].vertices[7], Vec3(1, 2, 3));
  ASSERT_EQ(shapes[2].triangles.size(), 2u);
  expectVec(shapes[2].vertices[3], Vec3(1, 1, 5));
  ASSERT_EQ(shapes[2].albedo.size(), 2u);
  expectVec(shapes[2].albedo[1], Vec3(0.9f, 0.1f, 0.1f));
  EXPECT_TRUE(shapes[2].normals.empty());  // no `vn`: flat shading
}
