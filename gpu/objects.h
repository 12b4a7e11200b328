#pragma once
/// Scene objects on the GPU (docs/objects.md): every object's surface as one list of
/// triangles in a storage buffer, drawn attribute-less by objects.vert.glsl from gl_VertexID.
/// Spheres are tessellated (their CPU twin is Embree's analytic sphere); boxes and meshes are
/// their triangles (core/objects.h ObjectShape). The shadow maps (gpu/shadow_maps.h) and the
/// slice marcher's surface pass draw it. Members need a current context; objectVertices
/// does not.

#include <vector>

#include "core/objects.h"
#include "gpu/gl.h"

namespace scatterlab::gpu {

/// One triangle corner: objects.vert.glsl `ObjectVertex` (objectVertices[] at
/// BINDING_OBJECT_VERTICES). std430: position 0, normal 16, shading 32, albedo 48; stride 64.
struct GpuObjectVertex {
  Vec3 position{0.0f};  ///< world space
  float object = 0.0f;  ///< index into the scene's `objects`
  Vec3 normal{0.0f};    ///< geometric normal (the face's; a sphere's own at the corner), unit
  float pad0 = 0.0f;
  Vec3 shading{0.0f};  ///< shading normal (the OBJ's `vn`, else the geometric one), unit
  float pad1 = 0.0f;
  Vec3 albedo{0.0f};
  float pad2 = 0.0f;
};
static_assert(sizeof(GpuObjectVertex) == 64);

/// Longitude segments of a tessellated sphere (latitude rings: half as many). Its vertices lie
/// on the sphere; the chords fall inside it by at most r·(1 − cos(π/kSphereSegments)), 0.12 %
/// of the radius at 64.
inline constexpr int kSphereSegments = 64;

/// The triangle list of every object (3 corners per triangle, in object order). No context.
std::vector<GpuObjectVertex> objectVertices(const SceneObjects& objects,
                                            int sphereSegments = kSphereSegments);

/// The objects' triangles uploaded once.
class ObjectGeometry {
 public:
  /// Uploads objectVertices(objects). Needs the context.
  explicit ObjectGeometry(const SceneObjects& objects);
  GLsizei vertexCount() const { return count_; }
  /// Binds the vertex buffer at binding::kObjectVertices and draws every triangle with the
  /// bound program (which must use objects.vert.glsl) and an empty vertex array.
  void draw() const;

 private:
  Buffer vertices_;
  VertexArray vao_;
  GLsizei count_ = 0;
};

}  // namespace scatterlab::gpu
