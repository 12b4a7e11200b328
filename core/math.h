#pragma once
/// Small math vocabulary shared by every module. World space is right-handed, units arbitrary.

#include <algorithm>
#include <cmath>
#include <glm/glm.hpp>
#include <limits>

namespace scatterlab {

using Vec3 = glm::vec3;
using IVec3 = glm::ivec3;
using UVec3 = glm::uvec3;

inline constexpr float kPi = 3.14159265358979323846f;
inline constexpr float kInvFourPi = 1.0f / (4.0f * kPi);
inline constexpr float kInfinity = std::numeric_limits<float>::infinity();

/// Ray x(t) = origin + t * dir; dir is unit length.
struct Ray {
  Vec3 origin{0.0f};
  Vec3 dir{0.0f, 0.0f, 1.0f};
  Vec3 at(float t) const { return origin + t * dir; }
};

/// Axis-aligned box [min, max] in world space.
struct Box {
  Vec3 min{0.0f};
  Vec3 max{1.0f};

  Vec3 extent() const { return max - min; }
  Vec3 center() const { return 0.5f * (min + max); }
  bool contains(const Vec3& p) const {
    return p.x >= min.x && p.y >= min.y && p.z >= min.z && p.x <= max.x && p.y <= max.y &&
           p.z <= max.z;
  }
  bool valid() const { return max.x > min.x && max.y > min.y && max.z > min.z; }

  /// Slab test. Returns false when the ray misses; otherwise [t0, t1] is the overlap of the
  /// ray's parameter range [tmin, tmax] with the box (t0 <= t1).
  bool intersect(const Ray& r, float& t0, float& t1, float tmin = 0.0f,
                 float tmax = kInfinity) const {
    t0 = tmin;
    t1 = tmax;
    for (int a = 0; a < 3; ++a) {
      const float inv = 1.0f / r.dir[a];
      float tn = (min[a] - r.origin[a]) * inv;
      float tf = (max[a] - r.origin[a]) * inv;
      if (tn > tf) std::swap(tn, tf);
      // NaN (origin on a slab plane with dir parallel) keeps the previous bound.
      t0 = tn > t0 ? tn : t0;
      t1 = tf < t1 ? tf : t1;
      if (t0 > t1) return false;
    }
    return true;
  }
};

/// Hermite smoothstep on [e0, e1] (pbrt's SmoothStep): 0 below e0, 1 above e1.
inline float smoothStep(float x, float e0, float e1) {
  if (e0 == e1) return x < e0 ? 0.0f : 1.0f;
  const float t = std::clamp((x - e0) / (e1 - e0), 0.0f, 1.0f);
  return t * t * (3.0f - 2.0f * t);
}

}  // namespace scatterlab
