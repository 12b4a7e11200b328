/// FusedLights (cpu/fused_march.h): LightFactor's lights laid out for the fast march's kernels.

#include "cpu/fused_march.h"

#include "core/stages.h"

namespace scatterlab {

FusedLights::FusedLights(const Scene& scene, const LampModel& lamp, bool glow)
    : hg(scene.medium.phase.type == Phase::Type::HenyeyGreenstein),
      g(scene.medium.phase.g),
      phase_(scene.medium.phase) {
  for (std::size_t i = 0; i < scene.lights.size(); ++i) {
    const Light& l = scene.lights[i];
    if (l.type == Light::Type::Directional) {
      directional_.push_back(l);
      continue;
    }
    ++count;
    px.push_back(l.position.x);
    py.push_back(l.position.y);
    pz.push_back(l.position.z);
    ir.push_back(l.intensity.x);
    ig.push_back(l.intensity.y);
    ib.push_back(l.intensity.z);
    ax.push_back(l.direction.x);
    ay.push_back(l.direction.y);
    az.push_back(l.direction.z);
    const bool spot = l.type == Light::Type::Spot;
    // A point light's falloff: smoothStep(x, −2, −1) = 1 for every cosine x ≥ −1.
    e0.push_back(spot ? l.cosOuter : -2.0f);
    e1.push_back(spot ? l.cosInner : -1.0f);
    k.push_back(lamp.k(i));
    this->glow.push_back(glow ? kGlowRatio / glowAngle(l) : 0.0f);
  }
}

Vec3 FusedLights::directional(const Vec3& toViewer) const {
  Vec3 a(0.0f);
  for (const Light& l : directional_) a += l.intensity * phase_.eval(l.direction, toViewer);
  return a;
}

}  // namespace scatterlab
