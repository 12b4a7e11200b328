#pragma once
/// Light sources (DESIGN.md §2). Transmittance and visibility are not applied here: these give
/// the unoccluded, unattenuated irradiance factor and the geometry towards the light.

#include "core/math.h"

namespace scatterlab {

struct Light {
  enum class Type { Point, Spot, Directional };
  Type type = Type::Point;
  Vec3 position{0.0f};                ///< point and spot: world position
  Vec3 direction{0.0f, -1.0f, 0.0f};  ///< spot: axis; directional: the way light travels (unit)
  Vec3 intensity{1.0f};   ///< point/spot: radiant intensity I (RGB); directional: irradiance
  float cosInner = 1.0f;  ///< spot: cos of the inner half-angle (full intensity inside)
  float cosOuter = 0.0f;  ///< spot: cos of the outer half-angle (zero outside)

  /// Spot light angular falloff for a unit direction `fromLight` (light towards the point):
  /// 1 inside the inner cone, 0 outside the outer one, smoothstep of the cosine in between
  /// (pbrt-v4's SpotLight). Shared with the GPU shaders (gpu/shaders/common.glsl).
  float spotFalloff(const Vec3& fromLight) const {
    return smoothStep(glm::dot(fromLight, direction), cosOuter, cosInner);
  }

  /// Geometry towards the light from world point x.
  struct Incident {
    Vec3 toLight;     ///< unit direction from x towards the light
    float distance;   ///< distance to the light; infinity for directional lights
    Vec3 irradiance;  ///< I·falloff/d² (point, spot) or the sun's irradiance (directional)
  };

  /// Returns false when x receives nothing (outside a spot cone, or at the light position).
  bool incident(const Vec3& x, Incident& out) const {
    if (type == Type::Directional) {
      out.toLight = -direction;
      out.distance = kInfinity;
      out.irradiance = intensity;
      return true;
    }
    const Vec3 d = position - x;
    const float dist2 = glm::dot(d, d);
    if (dist2 <= 0.0f) return false;
    const float dist = std::sqrt(dist2);
    out.toLight = d / dist;
    out.distance = dist;
    float f = 1.0f;
    if (type == Type::Spot) {
      f = spotFalloff(-out.toLight);
      if (f <= 0.0f) return false;
    }
    out.irradiance = intensity * (f / dist2);
    return true;
  }
};

}  // namespace scatterlab
