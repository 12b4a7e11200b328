#pragma once
/// Scene objects (DESIGN.md §2, docs/scene-format.md `objects`): spheres, boxes and triangle
/// meshes (OBJ) with Lambertian albedo, inside or outside the medium. They stop camera rays,
/// reflect light and occlude every light (volumetric shadows). Visibility is ray traced by
/// Embree; its BVH is built once, when the scene is parsed, and shared by every copy of the
/// scene (the object is immutable and its queries are thread-safe). Embree does not appear in
/// this header.

#include <filesystem>
#include <memory>
#include <string>
#include <vector>

#include "core/math.h"
#include "core/params.h"

namespace scatterlab {

/// The largest coordinate magnitude of any point a scene places (medium box, camera, lights,
/// object geometry, Gaussian centres; docs/reliability.md). Embree traces only rays whose
/// origins lie within +-1.8e18 (its FLT_LARGE; beyond, its `ray.valid()` assertion aborts the
/// process), and every ray origin is a point of the scene or a hit on an object, so within this
/// bound with a wide margin; single precision keeps ~1e8 units of resolution there.
inline constexpr double kMaxCoordinate = 1e15;

/// The first surface along a ray.
struct SurfaceHit {
  float t = 0.0f;       ///< ray parameter of the hit (world units along the unit direction)
  Vec3 position{0.0f};  ///< world point
  Vec3 normal{0.0f};    ///< unit geometric normal, turned to face the ray's origin
  /// Unit shading normal on the same side: the mesh's interpolated vertex normals where its
  /// OBJ has them (`vn`), else the geometric normal.
  Vec3 shading{0.0f};
  Vec3 albedo{0.0f};  ///< Lambertian albedo (RGB, [0, 1])
  int object = -1;    ///< index into the scene's `objects` array
};

/// What one parsed object is (for reports and `scatterlab info`).
struct ObjectInfo {
  std::string type;         ///< "sphere", "box" or "mesh"
  long long triangles = 0;  ///< 0 for spheres
  Box bounds;               ///< world-space bounds
};

/// One object's surface as a rasteriser needs it (the GPU backend's shadow maps and camera
/// pass): a sphere's centre and radius, or triangles in world space. Same data as the BVH.
struct ObjectShape {
  enum class Kind { Sphere, Triangles };
  Kind kind = Kind::Triangles;
  Vec3 center{0.0f};                  ///< Sphere: centre (world)
  float radius = 0.0f;                ///< Sphere: radius (world units)
  std::vector<Vec3> vertices;         ///< Triangles: world-space vertices
  std::vector<glm::uvec3> triangles;  ///< Triangles: indices into vertices
  std::vector<Vec3> albedo;           ///< one value, or one per triangle
  std::vector<Vec3> normals;          ///< Triangles: unit shading normals, 3 per triangle, or empty
};

class SceneObjects {
 public:
  /// Parses the `objects` array (each element an object read strictly: an unknown key or a
  /// bad value is a ConfigError naming `objects[i].key`; an unreadable or malformed OBJ or
  /// .mtl an IoError naming it) and builds the BVH. Mesh paths are relative to `baseDir`.
  /// Every point of every object (sphere centre ± radius, box corners, mesh vertices after
  /// the transform) must lie within +-kMaxCoordinate.
  static std::shared_ptr<const SceneObjects> parse(std::vector<Params> items,
                                                   const std::filesystem::path& baseDir);
  ~SceneObjects();
  SceneObjects(const SceneObjects&) = delete;
  SceneObjects& operator=(const SceneObjects&) = delete;

  const std::vector<ObjectInfo>& objects() const;
  /// The surfaces, by object index (for rasterisers; the CPU traces the BVH instead).
  const std::vector<ObjectShape>& shapes() const;
  long long triangles() const;
  /// Union of the objects' bounds.
  Box bounds() const;
  /// Offset (world units) by which secondary rays leave a surface, scaled to the scene.
  float epsilon() const;

  /// The first hit along `r` (unit direction) with t in (tmin, tmax); false when none.
  /// A ray Embree cannot trace (an origin beyond +-1.8e18, a non-finite direction, a NaN
  /// tmin or tmax) hits nothing instead of aborting; parsed scenes never make one
  /// (kMaxCoordinate).
  bool intersect(const Ray& r, float tmin, float tmax, SurfaceHit& hit) const;
  /// Whether an object blocks origin + t·dir for t in (tmin, tmax) (dir unit; tmax may be
  /// infinity for directional lights). An untraceable ray (see intersect) is not occluded.
  bool occluded(const Vec3& origin, const Vec3& dir, float tmin, float tmax) const;

 private:
  struct Impl;
  explicit SceneObjects(std::unique_ptr<Impl> impl);
  std::unique_ptr<Impl> impl_;
};

/// The key table of one object (docs/scene-format.md, tests/methods/test_key_docs.cpp).
const std::vector<KeyDoc>& objectKeyDocs();

}  // namespace scatterlab
