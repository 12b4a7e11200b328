/// FusedLights (cpu/fused_march.h): LightFactor's lights laid out for the fast march's kernels.

#include "cpu/fused_march.h"

#include <algorithm>
#include <cmath>

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
    this->glow.push_back(glow ? glowScale(l) : 0.0f);
  }
}

bool FusedLights::glowMean(int j, const FusedFactor& f, float t, float dt, float out[3]) const {
  const Vec3 p(px[j], py[j], pz[j]), o(f.origin[0], f.origin[1], f.origin[2]),
      d(f.dir[0], f.dir[1], f.dir[2]);
  const int n = glowSubsteps(glowDistance(p, o + t * d, d, dt), glow[j] * dt);
  if (n <= 1) return false;
  const float gg = 1.0f + g * g, g2 = 2.0f * g, hgNum = kInvFourPi * (1.0f - g * g);
  float s0 = 0.0f, s1 = 0.0f, s2 = 0.0f;
  for (int m = 0; m < n; ++m) {
    const float tm = glowSubstepT(t, dt, m, n);
    const float dx = px[j] - (f.origin[0] + tm * f.dir[0]),
                dy = py[j] - (f.origin[1] + tm * f.dir[1]),
                dz = pz[j] - (f.origin[2] + tm * f.dir[2]);
    const float d2 = dx * dx + dy * dy + dz * dz;
    if (!(d2 > 0.0f)) continue;
    const float dist = std::sqrt(d2);
    const float tx = dx / dist, ty = dy / dist, tz = dz / dist;
    float cone = 1.0f;
    if (e0[j] > -2.0f) {  // a spot light
      const float c = -tx * ax[j] + -ty * ay[j] + -tz * az[j];
      if (e0[j] == e1[j]) {
        cone = c < e0[j] ? 0.0f : 1.0f;
      } else {
        const float u = std::min(std::max((c - e0[j]) / (e1[j] - e0[j]), 0.0f), 1.0f);
        cone = u * u * (3.0f - 2.0f * u);
      }
    }
    if (!(cone > 0.0f)) continue;
    float phase = kInvFourPi;
    if (hg) {
      const float cosT = -tx * f.toViewer[0] + -ty * f.toViewer[1] + -tz * f.toViewer[2];
      const float denom = gg - g2 * cosT;
      phase = hgNum / (denom * std::sqrt(denom));
    }
    if (k[j] > 0.0f) {
      const float q = k[j] * dist;
      phase = phase * lampTransmittance(q);
    }
    const float s = cone / d2;
    s0 += ir[j] * s * phase;
    s1 += ig[j] * s * phase;
    s2 += ib[j] * s * phase;
  }
  out[0] = s0 / float(n);
  out[1] = s1 / float(n);
  out[2] = s2 / float(n);
  return true;
}

void FusedLights::setFarField(const FarField* far) {
  far_ = far && far->on() ? far : nullptr;
  farRadius = far_ ? far_->radius : 0.0f;
  farA = nullptr;
  if (!far_) return;
  for (int a = 0; a < 3; ++a) {
    farDims[a] = far_->dims[a];
    farLo[a] = far_->lo[a];
    farCell[a] = far_->cell[a];
  }
  if (3 * far_->a.size() < std::size_t(1) << 31) farA = &far_->a[0].x;
}

void FusedLights::farLookup(float x, float y, float z, float out[3]) const {
  const Vec3 a = far_->lookup(Vec3(x, y, z));
  out[0] = a.x;
  out[1] = a.y;
  out[2] = a.z;
}

void FusedLights::nearSpan(const FusedFactor& f, float ta, float tb, std::vector<int>& out) const {
  out.clear();
  const Vec3 o(f.origin[0], f.origin[1], f.origin[2]), d(f.dir[0], f.dir[1], f.dir[2]);
  // factorGroup skips a point light only where d² >= 4R² at every step; 2R(1 + 1e-4) keeps
  // every light it could evaluate.
  const float reach = 2.0f * farRadius * 1.0001f;
  for (int j = 0; j < count; ++j) {
    if (e0[j] > -2.0f) {  // a spot light: always evaluated
      out.push_back(j);
      continue;
    }
    const Vec3 p(px[j], py[j], pz[j]);
    const float t = std::clamp(glm::dot(p - o, d), ta, tb);
    if (glm::length(p - (o + t * d)) < reach) out.push_back(j);
  }
}

Vec3 FusedLights::directional(const Vec3& toViewer) const {
  Vec3 a(0.0f);
  for (const Light& l : directional_) a += l.intensity * phase_.eval(l.direction, toViewer);
  return a;
}

}  // namespace scatterlab
