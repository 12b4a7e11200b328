/// The fast march's avx2 kernel (cpu/fused_march.h). Built with -mavx2 -mfma -mf16c and
/// called only where the CPU has them (cpuHasAvx2Kernel). The lookup is written with the
/// intrinsics xsimd 8 has no spelling for (128-bit halves of a 256-bit register, F16C).

#if defined(__AVX2__) && defined(__FMA__) && defined(__F16C__)
#include <immintrin.h>

#include "cpu/fused_march.h"
// Included here, outside the kernel namespace, so that fused_march_impl.h only adds the loop.
#include <xsimd/xsimd.hpp>

namespace scatterlab {
namespace avx2_kernel {
#include "cpu/fused_march_impl.h"

/// A cell's corners as four 8-float registers, each the (D, S) of the cell's two x neighbours
/// (contiguous in memory): lerp along y, then z (8 wide), then x between the two halves.
/// `o`: the base corner's offset in floats (or halves), f: the fractions.
template <bool Half>
inline void lookupAt(const FusedVolumeView& v, std::ptrdiff_t o, float fx, float fy, float fz,
                     float* out) {
  const std::ptrdiff_t dy = 4 * v.row, dz = 4 * v.slice;
  __m256 p00, p10, p01, p11;
  if constexpr (Half) {
    const std::uint16_t* p = v.f16 + o;
    const auto load = [](const std::uint16_t* q) {
      return _mm256_cvtph_ps(_mm_loadu_si128(reinterpret_cast<const __m128i*>(q)));
    };
    p00 = load(p);
    p10 = load(p + dy);
    p01 = load(p + dz);
    p11 = load(p + dz + dy);
  } else {
    const float* p = v.f32 + o;
    p00 = _mm256_loadu_ps(p);
    p10 = _mm256_loadu_ps(p + dy);
    p01 = _mm256_loadu_ps(p + dz);
    p11 = _mm256_loadu_ps(p + dz + dy);
  }
  const __m256 by = _mm256_set1_ps(fy), bz = _mm256_set1_ps(fz);
  const __m256 q0 = _mm256_fmadd_ps(by, _mm256_sub_ps(p10, p00), p00);
  const __m256 q1 = _mm256_fmadd_ps(by, _mm256_sub_ps(p11, p01), p01);
  const __m256 r = _mm256_fmadd_ps(bz, _mm256_sub_ps(q1, q0), q0);
  const __m128 lo = _mm256_castps256_ps128(r), hi = _mm256_extractf128_ps(r, 1);
  __m128 res = _mm_fmadd_ps(_mm_set1_ps(fx), _mm_sub_ps(hi, lo), lo);
  if constexpr (Half) res = _mm_mul_ps(res, _mm_loadu_ps(v.scale));
  _mm_store_ps(out, res);
}

/// spanLoop<8> with the cells of the eight steps of a group found 8 wide (clamp, base corner,
/// fractions and offsets of cellOf as vectors; offsets in 32 bits: at most 512³ · 4 < 2³¹).
template <bool Half>
void spanAvx2(const FusedVolumeView& v, const FusedMarchConstants& c, const FusedRay& r, int i,
              int end, FusedMarchState& s, const FusedFactor* factor) {
  using B8 = xsimd::make_sized_batch_t<float, 8>;
  const __m256 lane = _mm256_setr_ps(0, 1, 2, 3, 4, 5, 6, 7), zero = _mm256_setzero_ps();
  __m256 u0[3], du[3], maxI[3];
  __m256i maxB[3];
  for (int a = 0; a < 3; ++a) {
    u0[a] = _mm256_set1_ps(r.u0[a]);
    du[a] = _mm256_set1_ps(r.du[a]);
    maxI[a] = _mm256_set1_ps(v.maxIndex[a]);
    maxB[a] = _mm256_set1_epi32(v.maxBase[a]);
  }
  const __m256i row = _mm256_set1_epi32(int(v.row)), slice = _mm256_set1_epi32(int(v.slice));
  float L0 = s.L[0], L1 = s.L[1], L2 = s.L[2], T = s.T, wt = s.wt;
  const float minT = c.minT, ratio = c.ratio;
  for (; i < end && T > minT; i += 8) {
    const int q1 = end - i < 8 ? end - i : 8;
    const __m256 k = _mm256_add_ps(_mm256_set1_ps(float(i)), lane);
    alignas(32) float F[3][8];
    alignas(32) int O[8];
    __m256i off[3];
    for (int a = 0; a < 3; ++a) {
      // max(u, 0) returns 0 for NaN (the second operand), as cellOf's `u > 0 ? u : 0`.
      __m256 u = _mm256_max_ps(_mm256_fmadd_ps(k, du[a], u0[a]), zero);
      u = _mm256_min_ps(u, maxI[a]);
      off[a] = _mm256_min_epi32(_mm256_cvttps_epi32(u), maxB[a]);
      _mm256_store_ps(F[a], _mm256_sub_ps(u, _mm256_cvtepi32_ps(off[a])));
    }
    const __m256i o = _mm256_add_epi32(off[0], _mm256_add_epi32(_mm256_mullo_epi32(off[1], row),
                                                                _mm256_mullo_epi32(off[2], slice)));
    _mm256_store_si256(reinterpret_cast<__m256i*>(O), _mm256_slli_epi32(o, 2));
    alignas(32) float V[8][4], D[8];
    for (int q = 0; q < 8; ++q) D[q] = 0.0f;
    for (int q = 0; q < q1; ++q) {
      lookupAt<Half>(v, O[q], F[0][q], F[1][q], F[2][q], V[q]);
      D[q] = V[q][0] > 0.0f ? V[q][0] : 0.0f;
    }
    if (factor) factorGroup<8>(*factor, r, i, q1, V);
    alignas(32) float a[8];
    (xsimd::exp(B8(-c.sigmaT) * B8::load_aligned(D) * B8(r.dt))).store_aligned(a);
    accumulateGroup<8>(V, D, a, i, q1, r, ratio, minT, L0, L1, L2, T, wt);
  }
  s.L[0] = L0;
  s.L[1] = L1;
  s.L[2] = L2;
  s.T = T;
  s.wt = wt;
}

}  // namespace avx2_kernel

namespace detail {
void fusedSpanAvx2(const FusedVolumeView& v, const FusedMarchConstants& c, const FusedRay& r, int i,
                   int end, FusedMarchState& s, const FusedFactor* factor) {
  if (v.f16)
    avx2_kernel::spanAvx2<true>(v, c, r, i, end, s, factor);
  else
    avx2_kernel::spanAvx2<false>(v, c, r, i, end, s, factor);
}
}  // namespace detail

}  // namespace scatterlab

#else  // not x86-64: never chosen (cpuHasAvx2Kernel is false)

#include "cpu/fused_march.h"

namespace scatterlab::detail {
void fusedSpanAvx2(const FusedVolumeView& v, const FusedMarchConstants& c, const FusedRay& r, int i,
                   int end, FusedMarchState& s, const FusedFactor* factor) {
  fusedSpanSse2(v, c, r, i, end, s, factor);
}
}  // namespace scatterlab::detail

#endif
