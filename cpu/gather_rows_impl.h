#pragma once
/// The body of the Eq. 4 gather's row loop (cpu/gather_rows.h), included by gather_rows.cpp
/// (baseline x86-64: 4 lanes) and gather_rows_avx2.cpp (-mavx2: 8 lanes, chosen at run time).
/// Both are compiled with -ffast-math and without FMA, so both compute the same operations
/// (a reciprocal square root plus one Newton step, see gather_rows.h) lane by lane.

#include <algorithm>
#include <cmath>

#include "cpu/gather_rows.h"

namespace scatterlab::gather_detail {
namespace {

/// The one body of the three row functions: kOcc multiplies each weight by occ[i], kBounded
/// clamps each Taylor estimate to [lo, hi] before it is weighted. Compile-time switches, so
/// every instantiation is a plain vectorisable loop (a per-voxel test of an optional pointer
/// stopped GCC vectorising it: 34 → 58 ms on smoke1), and the paper's instantiation
/// (gradientRow) computes exactly what it computed before the switches existed.
template <bool kOcc, bool kBounded>
inline void row(float* __restrict r0, float* __restrict g0, float* __restrict b0,
                float* __restrict w0, int i0, int i1, float lox, float hx, float px, float c,
                float R, float eps, Vec3 base, Vec3 gx, const float* __restrict occ, float lo,
                float hi) {
  const float R2 = R * R, e2 = eps * eps * R2;
  const float br = base.x, bg = base.y, bb = base.z, gr = gx.x, gg = gx.y, gb = gx.z;
  const auto taylor = [=](float v) {  // [=]: lo, hi are unused when !kBounded
    if constexpr (kBounded) return std::min(std::max(v, lo), hi);
    return v;
  };
  for (int i = i0; i <= i1; ++i) {
    const float dx = (lox + (float(i) + 0.5f) * hx) - px;
    const float d2 = dx * dx + c;
    const float wAll = (kOcc ? occ[i] * R : R) / std::sqrt(std::max(d2, e2));
    const float w = d2 < R2 ? wAll : 0.0f;
    r0[i] += w * taylor(br + dx * gr);
    g0[i] += w * taylor(bg + dx * gg);
    b0[i] += w * taylor(bb + dx * gb);
    w0[i] += w;
  }
}

/// normaliseSpan's body (cpu/gather_rows.h).
inline void normalise(const float* __restrict r, const float* __restrict g,
                      const float* __restrict b, const float* __restrict w, int i0, int i1,
                      float* __restrict qr, float* __restrict qg, float* __restrict qb) {
  for (int i = i0; i <= i1; ++i) {
    const float q = w[i] > 0.0f ? w[i] : 1.0f;
    const float vr = r[i] / q, vg = g[i] / q, vb = b[i] / q;
    qr[i] = vr < 0.0f ? 0.0f : vr;
    qg[i] = vg < 0.0f ? 0.0f : vg;
    qb[i] = vb < 0.0f ? 0.0f : vb;
  }
}

}  // namespace
}  // namespace scatterlab::gather_detail
