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
    if (factor) factor->scale(factor->ctx, i, q1, V);
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
