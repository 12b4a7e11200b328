#include "gpu/objects.h"

#include "gpu/bindings.h"

namespace scatterlab::gpu {

namespace {

void addSphere(const ObjectShape& s, int object, int segments, std::vector<GpuObjectVertex>& out) {
  const int rings = std::max(2, segments / 2);
  const auto corner = [&](int i, int j) {
    const float phi = 2.0f * kPi * float(i) / float(segments);
    const float theta = kPi * float(j) / float(rings);
    const Vec3 n(std::sin(theta) * std::cos(phi), std::cos(theta), std::sin(theta) * std::sin(phi));
    GpuObjectVertex v;
    v.position = s.center + s.radius * n;
    v.object = float(object);
    v.normal = v.shading = n;
    v.albedo = s.albedo[0];
    return v;
  };
  for (int j = 0; j < rings; ++j)
    for (int i = 0; i < segments; ++i) {
      const GpuObjectVertex a = corner(i, j), b = corner(i + 1, j), c = corner(i, j + 1),
                            d = corner(i + 1, j + 1);
      if (j > 0) out.insert(out.end(), {a, b, d});          // not degenerate at the north pole
      if (j < rings - 1) out.insert(out.end(), {a, d, c});  // nor at the south pole
    }
}

void addTriangles(const ObjectShape& s, int object, std::vector<GpuObjectVertex>& out) {
  for (std::size_t t = 0; t < s.triangles.size(); ++t) {
    const Vec3 p[3] = {s.vertices[s.triangles[t][0]], s.vertices[s.triangles[t][1]],
                       s.vertices[s.triangles[t][2]]};
    Vec3 n = glm::cross(p[1] - p[0], p[2] - p[0]);
    const float len = glm::length(n);
    n = len > 0.0f ? n / len : Vec3(0.0f, 1.0f, 0.0f);
    for (int k = 0; k < 3; ++k) {
      GpuObjectVertex v;
      v.position = p[k];
      v.object = float(object);
      v.normal = n;
      v.shading = s.normals.empty() ? n : s.normals[3 * t + k];
      v.albedo = s.albedo.size() == 1 ? s.albedo[0] : s.albedo[t];
      out.push_back(v);
    }
  }
}

}  // namespace

std::vector<GpuObjectVertex> objectVertices(const SceneObjects& objects, int sphereSegments) {
  std::vector<GpuObjectVertex> out;
  const auto& shapes = objects.shapes();
  for (std::size_t i = 0; i < shapes.size(); ++i) {
    if (shapes[i].kind == ObjectShape::Kind::Sphere)
      addSphere(shapes[i], int(i), sphereSegments, out);
    else
      addTriangles(shapes[i], int(i), out);
  }
  return out;
}

ObjectGeometry::ObjectGeometry(const SceneObjects& objects) : vao_("object triangles") {
  const std::vector<GpuObjectVertex> v = objectVertices(objects);
  vertices_ = Buffer(v.size() * sizeof(GpuObjectVertex), v.data(), 0, "object triangles");
  count_ = GLsizei(v.size());
}

void ObjectGeometry::draw() const {
  vertices_.bindBase(GL_SHADER_STORAGE_BUFFER, binding::kObjectVertices);
  glBindVertexArray(vao_.id());
  glDrawArrays(GL_TRIANGLES, 0, count_);
}

}  // namespace scatterlab::gpu
