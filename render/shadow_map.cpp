#include "render/shadow_map.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

namespace scatterlab {

namespace {

/// A unit vector perpendicular to w and a second one completing the frame.
void basis(const Vec3& w, Vec3& r, Vec3& u) {
  const Vec3 a = std::abs(w.y) < 0.9f ? Vec3(0.0f, 1.0f, 0.0f) : Vec3(1.0f, 0.0f, 0.0f);
  r = glm::normalize(glm::cross(a, w));
  u = glm::cross(w, r);
}

/// The outer half-angle up to which a spot light gets a single 2D map.
constexpr float kMaxSpotHalfAngleDeg = 80.0f;

}  // namespace

ShadowMap::ShadowMap(const Light& light, const SceneObjects& objects, const Box& medium,
                     int resolution)
    : res_(resolution) {
  if (light.type == Light::Type::Directional) {
    // Orthographic: texels over the medium box's shadow on the plane perpendicular to the
    // light, rays starting before every object and the box along the light's direction.
    ortho_ = true;
    Face f;
    f.forward = glm::normalize(light.direction);
    basis(f.forward, f.right, f.up);
    float u0 = kInfinity, u1 = -kInfinity, v0 = kInfinity, v1 = -kInfinity, s0 = kInfinity;
    const Box all{glm::min(medium.min, objects.bounds().min),
                  glm::max(medium.max, objects.bounds().max)};
    for (int c = 0; c < 8; ++c) {
      const Vec3 m((c & 1) ? medium.max.x : medium.min.x, (c & 2) ? medium.max.y : medium.min.y,
                   (c & 4) ? medium.max.z : medium.min.z);
      u0 = std::min(u0, glm::dot(m, f.right));
      u1 = std::max(u1, glm::dot(m, f.right));
      v0 = std::min(v0, glm::dot(m, f.up));
      v1 = std::max(v1, glm::dot(m, f.up));
      const Vec3 a((c & 1) ? all.max.x : all.min.x, (c & 2) ? all.max.y : all.min.y,
                   (c & 4) ? all.max.z : all.min.z);
      s0 = std::min(s0, glm::dot(a, f.forward));
    }
    uMin_ = u0;
    vMin_ = v0;
    cellU_ = std::max(u1 - u0, 1e-12f) / float(res_);
    cellV_ = std::max(v1 - v0, 1e-12f) / float(res_);
    start_ = s0 - 1e-3f * glm::length(all.extent());
    faces_.push_back(f);
  } else {
    origin_ = light.position;
    const float half = std::acos(std::clamp(light.cosOuter, -1.0f, 1.0f)) * 180.0f / kPi;
    if (light.type == Light::Type::Spot && half <= kMaxSpotHalfAngleDeg) {
      Face f;
      f.forward = glm::normalize(light.direction);
      basis(f.forward, f.right, f.up);
      f.tanHalf = std::tan(half * kPi / 180.0f);
      faces_.push_back(f);
    } else {
      // Cube map: +X, −X, +Y, −Y, +Z, −Z, 90° each.
      for (int a = 0; a < 3; ++a)
        for (const float s : {1.0f, -1.0f}) {
          Face f;
          f.forward = Vec3(0.0f);
          f.forward[a] = s;
          basis(f.forward, f.right, f.up);
          faces_.push_back(f);
        }
    }
  }
  depth_.assign(faces_.size() * std::size_t(res_) * res_, kInfinity);
  const int rows = int(faces_.size()) * res_;
  tbb::parallel_for(tbb::blocked_range<int>(0, rows), [&](const tbb::blocked_range<int>& rr) {
    for (int row = rr.begin(); row < rr.end(); ++row) {
      const Face& f = faces_[std::size_t(row / res_)];
      const int j = row % res_;
      for (int i = 0; i < res_; ++i) {
        SurfaceHit hit;
        float& d = depth_[std::size_t(row) * res_ + i];
        if (ortho_) {
          const Vec3 o = f.right * (uMin_ + (float(i) + 0.5f) * cellU_) +
                         f.up * (vMin_ + (float(j) + 0.5f) * cellV_) + f.forward * start_;
          if (objects.intersect(Ray{o, f.forward}, 0.0f, kInfinity, hit)) d = start_ + hit.t;
        } else {
          const float sx = ((float(i) + 0.5f) / float(res_) * 2.0f - 1.0f) * f.tanHalf;
          const float sy = ((float(j) + 0.5f) / float(res_) * 2.0f - 1.0f) * f.tanHalf;
          const Vec3 dir = glm::normalize(f.forward + sx * f.right + sy * f.up);
          if (objects.intersect(Ray{origin_, dir}, 0.0f, kInfinity, hit)) d = hit.t;
        }
      }
    }
  });
}

bool ShadowMap::lookup(int fi, const Vec3& x, int& i, int& j, float& depth, float& texel) const {
  const Face& f = faces_[std::size_t(fi)];
  float u, v;
  if (ortho_) {
    u = (glm::dot(x, f.right) - uMin_) / cellU_;
    v = (glm::dot(x, f.up) - vMin_) / cellV_;
    depth = glm::dot(x, f.forward);
    texel = std::max(cellU_, cellV_);
  } else {
    const Vec3 d = x - origin_;
    const float z = glm::dot(d, f.forward);
    if (!(z > 0.0f)) return false;
    u = (glm::dot(d, f.right) / (z * f.tanHalf) + 1.0f) * 0.5f * float(res_);
    v = (glm::dot(d, f.up) / (z * f.tanHalf) + 1.0f) * 0.5f * float(res_);
    depth = glm::length(d);
    texel = depth * 2.0f * f.tanHalf / float(res_);
  }
  if (!(u >= 0.0f && v >= 0.0f && u < float(res_) && v < float(res_))) return false;
  i = std::min(int(u), res_ - 1);
  j = std::min(int(v), res_ - 1);
  return true;
}

float ShadowMap::visibility(const Vec3& x) const {
  int face = 0;
  if (faces_.size() == 6) {
    // The cube face of the major axis of x − light.
    const Vec3 d = x - origin_;
    const Vec3 a = glm::abs(d);
    const int axis = a.x >= a.y && a.x >= a.z ? 0 : (a.y >= a.z ? 1 : 2);
    face = 2 * axis + (d[axis] >= 0.0f ? 0 : 1);
  }
  int i, j;
  float depth, texel;
  // Outside the map (behind a spot light, outside the directional map): nothing recorded.
  if (!lookup(face, x, i, j, depth, texel)) return 1.0f;
  const float stored = depth_[(std::size_t(face) * res_ + j) * res_ + i];
  return depth <= stored + 2.0f * texel ? 1.0f : 0.0f;
}

}  // namespace scatterlab
