#pragma once
/// The step loop shared by the fast march's kernels (cpu/fused_march.h). Included only by
/// cpu/fused_march_sse2.cpp and cpu/fused_march_avx2.cpp, each inside a namespace of its
/// own: the two are compiled for different instruction sets, so no function here may become a
/// symbol both define (the linker would keep one of them for both).

#include <xsimd/xsimd.hpp>

#include "cpu/fused_march.h"

/// Adds the steps i … i + q1 − 1 of a group to the running sums in step order (their lookups
/// V = (D, S), clamped densities D and e^(−σt·D·dt) in a), until T falls to minT.
template <int G>
inline void accumulateGroup(const float (&V)[G][4], const float (&D)[G], const float (&a)[G], int i,
                            int q1, const scatterlab::FusedRay& r, float ratio, float minT,
                            float& L0, float& L1, float& L2, float& T, float& wt) {
  for (int q = 0; q < q1 && T > minT; ++q) {
    if (!(D[q] > 0.0f)) continue;
    const float w = T * ratio * (1.0f - a[q]);
    L0 += w * V[q][1];
    L1 += w * V[q][2];
    L2 += w * V[q][3];
    wt += T * (1.0f - a[q]) * (r.t0 + (float(i + q) + 0.5f) * r.dt);
    T *= a[q];
  }
}

/// S = (V[q][1], V[q][2], V[q][3]) of steps i … i + q1 − 1 multiplied by A at their points
/// (FusedFactor): the point and spot lights G steps at once, light by light, each term as
/// LightFactor's (shading/transport.h; Light::incident, Phase::evalCos, LampModel), then the
/// directional lights' constant. Only steps with D > 0 and S ≠ 0 are scaled (the others add
/// nothing), and none is computed where no step of the group needs it. With a far field
/// (FusedLights::setFarField) a point light beyond 2R of all G steps is skipped, one within is
/// weighted by 1 − w, and the grid's part is added per step: LightFactor::overStep's sum.
template <int G>
inline void factorGroup(const scatterlab::FusedFactor& f, const scatterlab::FusedRay& r, int i,
                        int q1, float (&V)[G][4]) {
  using B = xsimd::make_sized_batch_t<float, G>;
  bool any = false;
  for (int q = 0; q < q1; ++q)
    any |= V[q][0] > 0.0f && (V[q][1] != 0.0f || V[q][2] != 0.0f || V[q][3] != 0.0f);
  if (!any) return;
  alignas(32) float tq[G];
  for (int q = 0; q < G; ++q) tq[q] = r.t0 + (float(i + q) + 0.5f) * r.dt;
  const B t = B::load_aligned(tq);
  const B x = B(f.origin[0]) + t * B(f.dir[0]), y = B(f.origin[1]) + t * B(f.dir[1]),
          z = B(f.origin[2]) + t * B(f.dir[2]);
  const B vx(f.toViewer[0]), vy(f.toViewer[1]), vz(f.toViewer[2]);
  const scatterlab::FusedLights& l = *f.lights;
  const float g = l.g, gg = 1.0f + g * g, g2 = 2.0f * g,
              hgNum = scatterlab::kInvFourPi * (1.0f - g * g);
  const float farR = l.farRadius, far2 = 4.0f * farR * farR;
  B a0(0.0f), a1(0.0f), a2(0.0f);
  const bool all = f.nearCount < 0;
  const int n = all ? l.count : f.nearCount;
  for (int jn = 0; jn < n; ++jn) {
    const int j = all ? jn : f.near[jn];
    const B dx = B(l.px[j]) - x, dy = B(l.py[j]) - y, dz = B(l.pz[j]) - z;
    const B d2 = dx * dx + dy * dy + dz * dz;
    // A point light (edges −2, −1) beyond 2R of every step: wholly in the far field's grid.
    const bool nearPart = farR > 0.0f && l.e0[j] == -2.0f;
    if (nearPart && xsimd::all(d2 >= B(far2))) continue;
    const B dist = xsimd::sqrt(d2);
    const B tx = dx / dist, ty = dy / dist, tz = dz / dist;  // towards the light
    // Falloff: smoothstep of cos(from the light, axis) between the edges (1 for point lights).
    B cone(1.0f);
    const float e0 = l.e0[j], e1 = l.e1[j];
    if (e0 > -2.0f) {  // a spot light (a point light's edges are −2, −1)
      const B c = -tx * B(l.ax[j]) + -ty * B(l.ay[j]) + -tz * B(l.az[j]);
      if (e0 == e1) {
        cone = xsimd::select(c < B(e0), B(0.0f), B(1.0f));
      } else {
        const B u = xsimd::min(xsimd::max((c - B(e0)) / B(e1 - e0), B(0.0f)), B(1.0f));
        cone = u * u * (B(3.0f) - B(2.0f) * u);
      }
    }
    B phase(scatterlab::kInvFourPi);
    if (l.hg) {
      const B cosT = -tx * vx + -ty * vy + -tz * vz;
      const B denom = B(gg) - B(g2) * cosT;
      phase = B(hgNum) / (denom * xsimd::sqrt(denom));
    }
    if (l.k[j] > 0.0f) {
      const B q = B(l.k[j]) * dist;
      phase = phase * scatterlab::lampTransmittance(q);
    }
    const B s = cone / d2;
    // Light::incident's cut: nothing at the light's own position or outside the cone.
    const auto lit = (d2 > B(0.0f)) & (cone > B(0.0f));
    B t0 = xsimd::select(lit, B(l.ir[j]) * s * phase, B(0.0f));
    B t1 = xsimd::select(lit, B(l.ig[j]) * s * phase, B(0.0f));
    B t2 = xsimd::select(lit, B(l.ib[j]) * s * phase, B(0.0f));
    // Near the light the term varies faster than a step: its mean over the step's substeps.
    // (The step's distance to the light is at least the midpoint's less half the step.)
    const B reach = B(l.glow[j] * r.dt);
    if (xsimd::any(dist < reach + B(0.5f * r.dt))) {
      alignas(32) float T[3][G];
      t0.store_aligned(T[0]);
      t1.store_aligned(T[1]);
      t2.store_aligned(T[2]);
      for (int q = 0; q < q1; ++q) {
        if (!(V[q][0] > 0.0f) || (V[q][1] == 0.0f && V[q][2] == 0.0f && V[q][3] == 0.0f)) continue;
        float m[3];
        if (l.glowMean(j, f, tq[q], r.dt, m)) {
          T[0][q] = m[0];
          T[1][q] = m[1];
          T[2][q] = m[2];
        }
      }
      t0 = B::load_aligned(T[0]);
      t1 = B::load_aligned(T[1]);
      t2 = B::load_aligned(T[2]);
    }
    if (nearPart) {  // its near part: 1 − smoothstep(R, 2R, distance) of the term
      const B u = xsimd::min(xsimd::max((dist - B(farR)) / B(farR), B(0.0f)), B(1.0f));
      const B keep = B(1.0f) - u * u * (B(3.0f) - B(2.0f) * u);
      t0 *= keep;
      t1 *= keep;
      t2 *= keep;
    }
    a0 += t0;
    a1 += t1;
    a2 += t2;
  }
  alignas(32) float A[3][G];
  (a0 + B(f.constant[0])).store_aligned(A[0]);
  (a1 + B(f.constant[1])).store_aligned(A[1]);
  (a2 + B(f.constant[2])).store_aligned(A[2]);
  if (farR > 0.0f && l.farA) {
    // The far field's part, FarField::lookup for the G steps at once: the same clamp, base
    // corner, fractions and lerps (glm::mix's a·(1 − t) + b·t), the corners gathered.
    using I = xsimd::batch<int32_t, typename B::arch_type>;
    static_assert(I::size == G, "one index per step");
    const B pos[3] = {x, y, z};
    B t[3];
    I base[3];
    for (int a = 0; a < 3; ++a) {
      const B u = xsimd::min(xsimd::max((pos[a] - B(l.farLo[a])) / B(l.farCell[a]), B(0.0f)),
                             B(float(l.farDims[a] - 1)));
      const B b = xsimd::min(xsimd::floor(u), B(float(l.farDims[a] - 2)));
      t[a] = u - b;
      base[a] = xsimd::batch_cast<int32_t>(b);
    }
    const int dx = 3, dy = 3 * l.farDims[0], dz = dy * l.farDims[1];
    const I o = base[2] * I(dz) + base[1] * I(dy) + base[0] * I(dx);
    const auto mix = [](const B& a, const B& b, const B& w) { return a * (B(1.0f) - w) + b * w; };
    alignas(32) float F[3][G];
    for (int c = 0; c < 3; ++c) {
      const float* p = l.farA + c;
      const auto at = [&](int off) { return B::gather(p, o + I(off)); };
      const B c00 = mix(at(0), at(dx), t[0]), c10 = mix(at(dy), at(dy + dx), t[0]),
              c01 = mix(at(dz), at(dz + dx), t[0]), c11 = mix(at(dz + dy), at(dz + dy + dx), t[0]);
      mix(mix(c00, c10, t[1]), mix(c01, c11, t[1]), t[2]).store_aligned(F[c]);
    }
    for (int q = 0; q < q1; ++q) {
      A[0][q] += F[0][q];
      A[1][q] += F[1][q];
      A[2][q] += F[2][q];
    }
  } else if (farR > 0.0f) {  // a grid too large for 32-bit offsets: per step, out of line
    alignas(32) float X[3][G];
    x.store_aligned(X[0]);
    y.store_aligned(X[1]);
    z.store_aligned(X[2]);
    for (int q = 0; q < q1; ++q) {  // every step, as above (the unscaled ones use none)
      float m[3];
      l.farLookup(X[0][q], X[1][q], X[2][q], m);
      A[0][q] += m[0];
      A[1][q] += m[1];
      A[2][q] += m[2];
    }
  }
  for (int q = 0; q < q1; ++q) {
    if (!(V[q][0] > 0.0f) || (V[q][1] == 0.0f && V[q][2] == 0.0f && V[q][3] == 0.0f)) continue;
    V[q][1] *= A[0][q];
    V[q][2] *= A[1][q];
    V[q][3] *= A[2][q];
  }
}

/// Marches steps [i, end) with `lookup(v, u, out)` writing (D, S.r, S.g, S.b) at index
/// coordinates u to out, S scaled by `factor` where there is one; exp of G steps at once.
template <int G, class Lookup>
inline void spanLoop(const scatterlab::FusedVolumeView& v, const scatterlab::FusedMarchConstants& c,
                     const scatterlab::FusedRay& r, int i, int end, scatterlab::FusedMarchState& s,
                     const scatterlab::FusedFactor* factor, const Lookup& lookup) {
  using Batch = xsimd::make_sized_batch_t<float, G>;
  float L0 = s.L[0], L1 = s.L[1], L2 = s.L[2], T = s.T, wt = s.wt;
  const float minT = c.minT, ratio = c.ratio;
  for (; i < end && T > minT; i += G) {
    const int q1 = end - i < G ? end - i : G;
    alignas(32) float V[G][4], D[G], a[G];
    for (int q = 0; q < G; ++q) D[q] = 0.0f;
    for (int q = 0; q < q1; ++q) {
      const float k = float(i + q);
      const float u[3] = {r.u0[0] + k * r.du[0], r.u0[1] + k * r.du[1], r.u0[2] + k * r.du[2]};
      lookup(v, u, V[q]);
      D[q] = V[q][0] > 0.0f ? V[q][0] : 0.0f;
    }
    if (factor) factorGroup<G>(*factor, r, i, q1, V);
    (xsimd::exp(Batch(-c.sigmaT) * Batch::load_aligned(D) * Batch(r.dt))).store_aligned(a);
    accumulateGroup<G>(V, D, a, i, q1, r, ratio, minT, L0, L1, L2, T, wt);
  }
  s.L[0] = L0;
  s.L[1] = L1;
  s.L[2] = L2;
  s.T = T;
  s.wt = wt;
}

/// Clamped base corner, fractions and voxel offset of index coordinates u (Grid3::sampleIndex).
inline std::ptrdiff_t cellOf(const scatterlab::FusedVolumeView& v, const float* u, float f[3]) {
  int b[3];
  for (int a = 0; a < 3; ++a) {
    float x = u[a] > 0.0f ? u[a] : 0.0f;  // also maps NaN to 0
    x = x < v.maxIndex[a] ? x : v.maxIndex[a];
    b[a] = int(x) < v.maxBase[a] ? int(x) : v.maxBase[a];
    f[a] = x - float(b[a]);
  }
  return b[2] * v.slice + b[1] * v.row + b[0];
}
