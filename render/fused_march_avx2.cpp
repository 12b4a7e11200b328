/// The fast march's avx2 kernel (render/fused_march.h). Built with -mavx2 -mfma -mf16c and
/// called only where the CPU has them (cpuHasAvx2Kernel). The lookup is written with the
/// intrinsics xsimd 8 has no spelling for (128-bit halves of a 256-bit register, F16C).

#if defined(__AVX2__) && defined(__FMA__) && defined(__F16C__)
#include <immintrin.h>

#include "render/fused_march.h"
// Included here, outside the kernel namespace, so that fused_march_impl.h only adds the loop.
#include <xsimd/xsimd.hpp>

namespace scatterlab {
namespace avx2_kernel {
#include "render/fused_march_impl.h"

/// A cell's corners as four 8-float registers, each the (D, S) of the cell's two x neighbours
/// (contiguous in memory): lerp along y, then z (8 wide), then x between the two halves.
template <bool Half>
struct Lookup {
  void operator()(const FusedVolumeView& v, const float* u, float* out) const {
    float f[3];
    const std::ptrdiff_t o = 4 * cellOf(v, u, f);
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
    const __m256 fy = _mm256_set1_ps(f[1]), fz = _mm256_set1_ps(f[2]);
    const __m256 q0 = _mm256_fmadd_ps(fy, _mm256_sub_ps(p10, p00), p00);
    const __m256 q1 = _mm256_fmadd_ps(fy, _mm256_sub_ps(p11, p01), p01);
    const __m256 r = _mm256_fmadd_ps(fz, _mm256_sub_ps(q1, q0), q0);
    const __m128 lo = _mm256_castps256_ps128(r), hi = _mm256_extractf128_ps(r, 1);
    __m128 res = _mm_fmadd_ps(_mm_set1_ps(f[0]), _mm_sub_ps(hi, lo), lo);
    if constexpr (Half) res = _mm_mul_ps(res, _mm_loadu_ps(v.scale));
    _mm_store_ps(out, res);
  }
};

}  // namespace avx2_kernel

namespace detail {
void fusedSpanAvx2(const FusedVolumeView& v, const FusedMarchConstants& c, const FusedRay& r, int i,
                   int end, FusedMarchState& s) {
  if (v.f16)
    avx2_kernel::spanLoop<8>(v, c, r, i, end, s, avx2_kernel::Lookup<true>{});
  else
    avx2_kernel::spanLoop<8>(v, c, r, i, end, s, avx2_kernel::Lookup<false>{});
}
void fusedLookupsAvx2(const FusedVolumeView& v, const FusedRay& r, int i, int count,
                      float (*out)[4]) {
  alignas(16) float tmp[8][4];
  if (v.f16)
    avx2_kernel::lookupSteps(v, r, i, count, tmp, avx2_kernel::Lookup<true>{});
  else
    avx2_kernel::lookupSteps(v, r, i, count, tmp, avx2_kernel::Lookup<false>{});
  for (int q = 0; q < count; ++q)
    for (int c = 0; c < 4; ++c) out[q][c] = tmp[q][c];
}
}  // namespace detail

}  // namespace scatterlab

#else  // not x86-64: never chosen (cpuHasAvx2Kernel is false)

#include "render/fused_march.h"

namespace scatterlab::detail {
void fusedSpanAvx2(const FusedVolumeView& v, const FusedMarchConstants& c, const FusedRay& r, int i,
                   int end, FusedMarchState& s) {
  fusedSpanSse2(v, c, r, i, end, s);
}
void fusedLookupsAvx2(const FusedVolumeView& v, const FusedRay& r, int i, int count,
                      float (*out)[4]) {
  fusedLookupsSse2(v, r, i, count, out);
}
}  // namespace scatterlab::detail

#endif
