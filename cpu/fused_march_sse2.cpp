/// The fast march's sse2 kernel (cpu/fused_march.h): the build's baseline instruction set,
/// 4-float batches of xsimd. Also the run-time choice between the kernels.

#include <Imath/half.h>

#include "core/cpu_features.h"
#include "core/error.h"
#include "cpu/fused_march.h"
// Included here, outside the kernel namespace, so that fused_march_impl.h only adds the loop.
#include <xsimd/xsimd.hpp>

namespace scatterlab {
namespace sse2_kernel {
#include "cpu/fused_march_impl.h"

using B4 = xsimd::make_sized_batch_t<float, 4>;

/// Trilinear (D, S) from eight 4-float corners, lerped x, y, z as Grid3::sampleIndex does.
inline B4 trilinear(const B4 c[8], const float f[3]) {
  const auto lerp = [](const B4& a, const B4& b, float t) { return a + (b - a) * B4(t); };
  const B4 c00 = lerp(c[0], c[1], f[0]), c10 = lerp(c[2], c[3], f[0]);
  const B4 c01 = lerp(c[4], c[5], f[0]), c11 = lerp(c[6], c[7], f[0]);
  return lerp(lerp(c00, c10, f[1]), lerp(c01, c11, f[1]), f[2]);
}

struct LookupF32 {
  void operator()(const FusedVolumeView& v, const float* u, float* out) const {
    float f[3];
    const float* p = v.f32 + 4 * cellOf(v, u, f);
    const std::ptrdiff_t dy = 4 * v.row, dz = 4 * v.slice;
    const B4 c[8] = {B4::load_unaligned(p),           B4::load_unaligned(p + 4),
                     B4::load_unaligned(p + dy),      B4::load_unaligned(p + dy + 4),
                     B4::load_unaligned(p + dz),      B4::load_unaligned(p + dz + 4),
                     B4::load_unaligned(p + dz + dy), B4::load_unaligned(p + dz + dy + 4)};
    trilinear(c, f).store_aligned(out);
  }
};

/// Half storage without F16C: Imath's conversion per value (its table), then as LookupF32.
struct LookupF16 {
  void operator()(const FusedVolumeView& v, const float* u, float* out) const {
    float f[3];
    const std::uint16_t* p = v.f16 + 4 * cellOf(v, u, f);
    const std::ptrdiff_t off[8] = {0,
                                   4,
                                   4 * v.row,
                                   4 * v.row + 4,
                                   4 * v.slice,
                                   4 * v.slice + 4,
                                   4 * (v.slice + v.row),
                                   4 * (v.slice + v.row) + 4};
    alignas(16) float w[8][4];
    B4 c[8];
    for (int k = 0; k < 8; ++k) {
      for (int ch = 0; ch < 4; ++ch) w[k][ch] = imath_half_to_float(p[off[k] + ch]);
      c[k] = B4::load_aligned(w[k]);
    }
    (trilinear(c, f) * B4::load_unaligned(v.scale)).store_aligned(out);
  }
};

}  // namespace sse2_kernel

namespace detail {
void fusedSpanSse2(const FusedVolumeView& v, const FusedMarchConstants& c, const FusedRay& r, int i,
                   int end, FusedMarchState& s, const FusedFactor* factor) {
  if (v.f16)
    sse2_kernel::spanLoop<4>(v, c, r, i, end, s, factor, sse2_kernel::LookupF16{});
  else
    sse2_kernel::spanLoop<4>(v, c, r, i, end, s, factor, sse2_kernel::LookupF32{});
}
}  // namespace detail

bool cpuHasAvx2Kernel() {
#if defined(__x86_64__) || defined(__i386__)
  const CpuFeatures& f = cpuFeatures();
  return f.avx2 && f.fma && f.f16c;
#else
  return false;
#endif
}

FusedSpanKernel fusedSpanKernel(MarchSimd simd) {
  if (simd == MarchSimd::Avx2 && !cpuHasAvx2Kernel())
    throw ConfigError(
        "'render.march_simd': avx2 asked for, but this CPU lacks AVX2, FMA or F16C (use auto or "
        "sse2)");
  if (simd == MarchSimd::Sse2 || !cpuHasAvx2Kernel()) return &detail::fusedSpanSse2;
  return &detail::fusedSpanAvx2;
}

std::string fusedKernelName(MarchSimd simd) {
  return fusedSpanKernel(simd) == &detail::fusedSpanAvx2 ? "avx2" : "sse2";
}

}  // namespace scatterlab
