#pragma once
/// The SIMD body of render/shadow_rays.h, included by shadow_rays.cpp (baseline x86-64: SSE2,
/// 4 lanes) and shadow_rays_avx2.cpp (compiled with -mavx2 -mfma: 8 lanes, hardware gathers).
/// Only plain arithmetic and xsimd batches of the including file's architecture: no inline
/// function of another library is instantiated here, so nothing compiled for AVX2 can be
/// merged by the linker into the baseline path.

#include <xsimd/xsimd.hpp>

#include "render/shadow_rays.h"

namespace scatterlab::shadow_detail {

/// Σ_i D(u0 + i·du), i = 0..n−1, each lookup as Grid3::sampleIndex (clamped trilinear), lane l
/// of a batch taking step i + l. Stops after the first block of 8 steps at whose end the sum
/// exceeds sumMax (as the scalar stopping opticalDepth).
template <class Arch>
float densitySum(const DensityLayout& g, const float u0[3], const float du[3], int n,
                 float sumMax) {
  using B = xsimd::batch<float, Arch>;
  using I = xsimd::batch<std::int32_t, Arch>;
  constexpr int W = int(B::size);
  static_assert(8 % W == 0, "a block of 8 steps is whole batches");
  alignas(64) float lane[W];
  for (int l = 0; l < W; ++l) lane[l] = float(l);
  const B iota = B::load_aligned(lane);
  const B zero(0.0f);
  const B mx(g.maxIndex[0]), my(g.maxIndex[1]), mz(g.maxIndex[2]);
  const I bx(g.maxBase[0]), by(g.maxBase[1]), bz(g.maxBase[2]);
  const I sy(g.rowStride), sz(g.sliceStride);
  const int dx = g.step[0], dy = g.step[1], dz = g.step[2];
  const I ox(dx), oy(dy), oyx(dy + dx), oz(dz), ozx(dz + dx), ozy(dz + dy), ozyx(dz + dy + dx);
  const B ux0(u0[0]), uy0(u0[1]), uz0(u0[2]), dux(du[0]), duy(du[1]), duz(du[2]);
  const float* d = g.data;
  B acc(0.0f);
  for (int i = 0; i < n;) {
    const int blockEnd = i + 8 < n ? i + 8 : n;
    for (; i < blockEnd; i += W) {
      const B t = B(float(i)) + iota;
      // `u > 0 ? u : 0` then `u < max ? u : max`, as sampleIndex (NaN reads voxel 0).
      B ux = ux0 + t * dux, uy = uy0 + t * duy, uz = uz0 + t * duz;
      ux = xsimd::select(ux > zero, ux, zero);
      uy = xsimd::select(uy > zero, uy, zero);
      uz = xsimd::select(uz > zero, uz, zero);
      ux = xsimd::select(ux < mx, ux, mx);
      uy = xsimd::select(uy < my, uy, my);
      uz = xsimd::select(uz < mz, uz, mz);
      const I ix = xsimd::min(xsimd::to_int(ux), bx);
      const I iy = xsimd::min(xsimd::to_int(uy), by);
      const I iz = xsimd::min(xsimd::to_int(uz), bz);
      const B fx = ux - xsimd::to_float(ix), fy = uy - xsimd::to_float(iy),
              fz = uz - xsimd::to_float(iz);
      const I base = ix + iy * sy + iz * sz;
      const auto at = [d](const I& idx) { return B::gather(d, idx); };
      const B p0 = at(base);
      const B c00 = p0 + (at(base + ox) - p0) * fx;
      const B p1 = at(base + oy);
      const B c10 = p1 + (at(base + oyx) - p1) * fx;
      const B p2 = at(base + oz);
      const B c01 = p2 + (at(base + ozx) - p2) * fx;
      const B p3 = at(base + ozy);
      const B c11 = p3 + (at(base + ozyx) - p3) * fx;
      const B c0 = c00 + (c10 - c00) * fy;
      const B c1 = c01 + (c11 - c01) * fy;
      const B v = c0 + (c1 - c0) * fz;
      acc += xsimd::select(t < B(float(n)), v, zero);
    }
    if (xsimd::hadd(acc) > sumMax) break;
  }
  return xsimd::hadd(acc);
}

}  // namespace scatterlab::shadow_detail
