#include "core/camera.h"

#include "core/error.h"

namespace scatterlab {

void Camera::frame(Vec3& forward, Vec3& right, Vec3& trueUp) const {
  const Vec3 f = lookAt - position;
  if (glm::length(f) <= 0.0f) throw ConfigError("camera: position equals look_at");
  forward = glm::normalize(f);
  const Vec3 r = glm::cross(forward, up);
  if (glm::length(r) < 1e-6f * glm::length(up))
    throw ConfigError("camera.up is parallel to the view direction");
  right = glm::normalize(r);
  trueUp = glm::cross(right, forward);
}

Camera::RayGenerator Camera::rayGenerator() const {
  RayGenerator g;
  frame(g.forward, g.right, g.up);
  g.origin = position;
  g.sy = std::tan(0.5f * fovYDeg * kPi / 180.0f);
  g.sx = g.sy * float(width) / float(height);
  g.width = width;
  g.height = height;
  return g;
}

Camera::DepthRange Camera::viewDepthRange(const RayGenerator& gen, const Box& b) {
  DepthRange r{kInfinity, -kInfinity};
  for (int c = 0; c < 8; ++c) {
    const Vec3 p((c & 1) ? b.max.x : b.min.x, (c & 2) ? b.max.y : b.min.y,
                 (c & 4) ? b.max.z : b.min.z);
    const float z = glm::dot(p - gen.origin, gen.forward);
    r.near = std::min(r.near, z);
    r.far = std::max(r.far, z);
  }
  return r;
}

Ray Camera::primaryRay(int px, int py) const {
  return rayGenerator()(px, py);
}

bool Camera::project(const Vec3& p, float& px, float& py) const {
  Vec3 f, r, u;
  frame(f, r, u);
  const Vec3 d = p - position;
  const float z = glm::dot(d, f);
  if (z <= 0.0f) return false;
  const float tanHalf = std::tan(0.5f * fovYDeg * kPi / 180.0f);
  const float aspect = float(width) / float(height);
  const float sx = glm::dot(d, r) / z / (tanHalf * aspect);
  const float sy = glm::dot(d, u) / z / tanHalf;
  px = (sx + 1.0f) * 0.5f * width;
  py = (1.0f - sy) * 0.5f * height;
  return true;
}

}  // namespace scatterlab
