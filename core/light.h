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

  /// Geometry towards the light from x before anything is cut off: what incident() and the
  /// singular-light factorization (shading/transport.h) both start from.
  struct Geometry {
    Vec3 toLight;     ///< unit direction from x towards the light
    float distance;   ///< infinity for directional lights
    float distance2;  ///< distance²; infinity for directional lights
    float cone;       ///< spotFalloff towards x (spot lights), else 1
  };

  /// Returns false only at a point or spot light's own position.
  bool geometry(const Vec3& x, Geometry& g) const {
    g.cone = 1.0f;
    if (type == Type::Directional) {
      g.toLight = -direction;
      g.distance = g.distance2 = kInfinity;
      return true;
    }
    const Vec3 d = position - x;
    g.distance2 = glm::dot(d, d);
    if (g.distance2 <= 0.0f) return false;
    g.distance = std::sqrt(g.distance2);
    g.toLight = d / g.distance;
    if (type == Type::Spot) g.cone = spotFalloff(-g.toLight);
    return true;
  }

  /// Returns false when x receives nothing (outside a spot cone, or at the light position).
  bool incident(const Vec3& x, Incident& out) const {
    Geometry g;
    if (!geometry(x, g) || g.cone <= 0.0f) return false;
    out.toLight = g.toLight;
    out.distance = g.distance;
    out.irradiance = type == Type::Directional ? intensity : intensity * (g.cone / g.distance2);
    return true;
  }
};

}  // namespace scatterlab
