#pragma once
/// The SIMD body of cpu/shadow_rays.h, included by shadow_rays.cpp (baseline x86-64: SSE2,
/// 4 lanes) and shadow_rays_avx2.cpp (compiled with -mavx2 -mfma: 8 lanes, hardware gathers).
/// Only plain arithmetic and xsimd batches of the including file's architecture: no inline
/// function of another library is instantiated here, so nothing compiled for AVX2 can be
/// merged by the linker into the baseline path.

#include <xsimd/xsimd.hpp>

#include <type_traits>

#include "cpu/shadow_rays.h"

namespace scatterlab::shadow_detail {

/// d[idx[l]] per lane. xsimd 8.1's batch::gather takes its generic path (a scalar loop, not
/// inlined: 30 % of `exact` in perf) even for AVX2, so the AVX2 instruction is named here.
template <class Arch>
inline xsimd::batch<float, Arch> gatherLanes(const float* d,
                                             const xsimd::batch<std::int32_t, Arch>& idx) {
#if defined(__AVX2__)
  if constexpr (std::is_same_v<Arch, xsimd::avx2>) return _mm256_i32gather_ps(d, idx, 4);
#endif
  constexpr std::size_t W = xsimd::batch<float, Arch>::size;
  alignas(64) std::int32_t i[W];
  alignas(64) float v[W];
  idx.store_aligned(i);
  for (std::size_t l = 0; l < W; ++l) v[l] = d[i[l]];
  return xsimd::batch<float, Arch>::load_aligned(v);
}

#if defined(__AVX2__)
/// AVX2, x neighbours as pairs: d[idx[l]] + (d[idx[l] + 1] − d[idx[l]])·f[l] with one 64-bit
/// gather per pair (two gathers of 4 pairs instead of two of 8 floats). The lanes come out in
/// the order (0, 1, 4, 5, 2, 3, 6, 7): `f` must be given in that order (kPairOrder).
inline __m256 pairLerp(const float* d, __m256i idx, __m256 f) {
  const auto* dd = reinterpret_cast<const double*>(d);
  // The masked form with a zero source: the plain one leaves GCC 12 warning of an
  // uninitialised source operand.
  const __m256d all = _mm256_castsi256_pd(_mm256_set1_epi64x(-1)), none = _mm256_setzero_pd();
  const __m256 a =
      _mm256_castpd_ps(_mm256_mask_i32gather_pd(none, dd, _mm256_castsi256_si128(idx), all, 4));
  const __m256 b = _mm256_castpd_ps(
      _mm256_mask_i32gather_pd(none, dd, _mm256_extracti128_si256(idx, 1), all, 4));
  const __m256 p0 = _mm256_shuffle_ps(a, b, 0x88), p1 = _mm256_shuffle_ps(a, b, 0xDD);
  return _mm256_fmadd_ps(_mm256_sub_ps(p1, p0), f, p0);
}
inline __m256 pairOrder(__m256 v) {
  return _mm256_permutevar8x32_ps(v, _mm256_setr_epi32(0, 1, 4, 5, 2, 3, 6, 7));
}
#endif

/// Σ_i D(u0 + i·du), i = 0..n−1, each lookup as Grid3::sampleIndex (clamped trilinear), lane l
/// of a batch taking step i + l. Stops after the first block of kShadowCheck steps at whose end
/// the sum exceeds sumMax. kPairs (AVX2 only, and only when x has more than one voxel): the x
/// neighbours are gathered as pairs (pairLerp) and the lanes are summed in pair order.
/// kInside: every step's index coordinate lies inside [0.01, maxIndex − 0.01] on every axis, so
/// the clamps are no-ops and are left out (the lanes past the last step are moved onto it).
inline constexpr int kShadowCheck = 32;
template <class Arch, bool kPairs, bool kInside>
float densitySumImpl(const DensityLayout& g, const float u0[3], const float du[3], int n,
                     float sumMax) {
  using B = xsimd::batch<float, Arch>;
  using I = xsimd::batch<std::int32_t, Arch>;
  constexpr int W = int(B::size);
  static_assert(kShadowCheck % W == 0, "a block of steps is whole batches");
#if defined(__AVX2__)
  static_assert(!kPairs || std::is_same_v<Arch, xsimd::avx2>, "pairs are AVX2 only");
#else
  static_assert(!kPairs, "pairs are AVX2 only");
#endif
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
  const B last(float(n - 1));
  B acc(0.0f);
  for (int i = 0; i < n;) {
    const int blockEnd = i + kShadowCheck < n ? i + kShadowCheck : n;
    for (; i < blockEnd; i += W) {
      B t = B(float(i)) + iota;
      B ux, uy, uz;
      I ix, iy, iz;
      if constexpr (kInside) {
        const B tt = xsimd::min(t, last);
        ux = ux0 + tt * dux;
        uy = uy0 + tt * duy;
        uz = uz0 + tt * duz;
        ix = xsimd::to_int(ux);
        iy = xsimd::to_int(uy);
        iz = xsimd::to_int(uz);
      } else {
        // `u > 0 ? u : 0` then `u < max ? u : max`, as sampleIndex (NaN reads voxel 0).
        ux = ux0 + t * dux;
        uy = uy0 + t * duy;
        uz = uz0 + t * duz;
        ux = xsimd::select(ux > zero, ux, zero);
        uy = xsimd::select(uy > zero, uy, zero);
        uz = xsimd::select(uz > zero, uz, zero);
        ux = xsimd::select(ux < mx, ux, mx);
        uy = xsimd::select(uy < my, uy, my);
        uz = xsimd::select(uz < mz, uz, mz);
        ix = xsimd::min(xsimd::to_int(ux), bx);
        iy = xsimd::min(xsimd::to_int(uy), by);
        iz = xsimd::min(xsimd::to_int(uz), bz);
      }
      B fx = ux - xsimd::to_float(ix), fy = uy - xsimd::to_float(iy), fz = uz - xsimd::to_float(iz);
      const I base = ix + iy * sy + iz * sz;
      B c00, c10, c01, c11;
#if defined(__AVX2__)
      if constexpr (kPairs) {
        fx = pairOrder(fx);
        fy = pairOrder(fy);
        fz = pairOrder(fz);
        t = pairOrder(t);
        c00 = pairLerp(d, base, fx);
        c10 = pairLerp(d, base + oy, fx);
        c01 = pairLerp(d, base + oz, fx);
        c11 = pairLerp(d, base + ozy, fx);
      }
#endif
      if constexpr (!kPairs) {
        const auto at = [d](const I& idx) { return gatherLanes<Arch>(d, idx); };
        const B p0 = at(base);
        c00 = p0 + (at(base + ox) - p0) * fx;
        const B p1 = at(base + oy);
        c10 = p1 + (at(base + oyx) - p1) * fx;
        const B p2 = at(base + oz);
        c01 = p2 + (at(base + ozx) - p2) * fx;
        const B p3 = at(base + ozy);
        c11 = p3 + (at(base + ozyx) - p3) * fx;
      }
      const B c0 = c00 + (c10 - c00) * fy;
      const B c1 = c01 + (c11 - c01) * fy;
      const B v = c0 + (c1 - c0) * fz;
      acc += xsimd::select(t < B(float(n)), v, zero);
    }
    if (xsimd::hadd(acc) > sumMax) break;
  }
  return xsimd::hadd(acc);
}

/// densitySumImpl with the clamps left out where the whole segment lies inside the grid.
template <class Arch, bool kPairs = false>
float densitySum(const DensityLayout& g, const float u0[3], const float du[3], int n,
                 float sumMax) {
  bool inside = n > 0;
  for (int a = 0; a < 3; ++a) {
    const float e = u0[a] + float(n - 1) * du[a];
    const float lo = u0[a] < e ? u0[a] : e, hi = u0[a] < e ? e : u0[a];
    inside = inside && lo >= 0.01f && hi <= g.maxIndex[a] - 0.01f;  // false for NaN
  }
  return inside ? densitySumImpl<Arch, kPairs, true>(g, u0, du, n, sumMax)
                : densitySumImpl<Arch, kPairs, false>(g, u0, du, n, sumMax);
}

}  // namespace scatterlab::shadow_detail
