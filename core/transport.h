#pragma once
/// Transport physics shared by every backend and stage (volume tracing, paper Sec. 4, Eq. 1):
/// transmittance along straight segments through the density volume, and the source radiance S(x,
/// ω) = Σ_l f(ω_l → ω)·E_l(x) of DESIGN.md §2. Header-only templates so the inner loops inline; no
/// virtual calls per step.

#include <vector>

#include "core/grid.h"
#include "core/light.h"
#include "core/phase.h"
#include "core/scene.h"

namespace scatterlab {

/// ∫ D along the segment a→b, restricted to `box`, by the midpoint rule with steps of at most
/// `step` (the paper's Δ1). `field(p)` returns D at a world point inside the box.
template <class Field>
float opticalDepth(const Field& field, const Box& box, const Vec3& a, const Vec3& b, float step) {
  const Vec3 d = b - a;
  const float len = glm::length(d);
  if (len <= 0.0f) return 0.0f;
  const Ray r{a, d / len};
  float t0, t1;
  if (!box.intersect(r, t0, t1, 0.0f, len) || t1 <= t0) return 0.0f;
  const int n = std::max(1, int(std::ceil((t1 - t0) / step)));
  const float dt = (t1 - t0) / float(n);
  float sum = 0.0f;
  for (int i = 0; i < n; ++i) sum += field(r.at(t0 + (float(i) + 0.5f) * dt));
  return sum * dt;
}

/// Fast path of opticalDepth for a DensityGrid covering `box`: marches in index space.
inline float opticalDepth(const DensityGrid& g, const Vec3& a, const Vec3& b, float step) {
  const Vec3 d = b - a;
  const float len = glm::length(d);
  if (len <= 0.0f) return 0.0f;
  const Ray r{a, d / len};
  float t0, t1;
  if (!g.bounds().intersect(r, t0, t1, 0.0f, len) || t1 <= t0) return 0.0f;
  const int n = std::max(1, int(std::ceil((t1 - t0) / step)));
  const float dt = (t1 - t0) / float(n);
  const Vec3 s = g.indexScale();
  const Vec3 u0 = r.at(t0 + 0.5f * dt) * s + g.indexOffset();
  const Vec3 du = r.dir * dt * s;
  float sum = 0.0f;
  for (int i = 0; i < n; ++i) sum += g.sampleIndex(u0 + float(i) * du);
  return sum * dt;
}

/// The far end of the segment from x towards a light: the light itself, or for directional
/// lights the point where the ray leaves the box (or x when it is outside).
inline Vec3 lightSegmentEnd(const Light& l, const Light::Incident& inc, const Box& box,
                            const Vec3& x) {
  if (l.type != Light::Type::Directional) return x + inc.toLight * inc.distance;
  float t0, t1;
  if (!box.intersect(Ray{x, inc.toLight}, t0, t1)) return x;
  return x + inc.toLight * t1;
}

/// Evaluates the source radiance S(x, ω) for the scene's lights through a density volume.
/// S excludes σs and D: the in-scattered radiance per unit length is σs·D(x)·S(x, ω).
class SourceRadiance {
 public:
  /// `delta1`: volume tracing step (world units). References must outlive this object.
  SourceRadiance(const Scene& scene, const DensityGrid& density, float delta1)
      : lights_(scene.lights),
        phase_(scene.medium.phase),
        sigmaT_(scene.medium.sigmaT),
        density_(density),
        delta1_(delta1) {}

  /// S at x for light leaving towards the viewer along unit `toViewer`.
  Vec3 operator()(const Vec3& x, const Vec3& toViewer) const {
    Vec3 s(0.0f);
    for (const Light& l : lights_) {
      Light::Incident inc;
      if (!l.incident(x, inc)) continue;
      const float tau =
          opticalDepth(density_, x, lightSegmentEnd(l, inc, density_.bounds(), x), delta1_);
      s += inc.irradiance * (phase_.eval(-inc.toLight, toViewer) * std::exp(-sigmaT_ * tau));
    }
    return s;
  }

 private:
  const std::vector<Light>& lights_;
  Phase phase_;
  float sigmaT_;
  const DensityGrid& density_;
  float delta1_;
};

}  // namespace scatterlab
