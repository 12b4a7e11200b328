// The AVX2 + FMA instantiation of cpu/shadow_rays_kernel.h; this file alone is compiled
// with -mavx2 -mfma (cpu/CMakeLists.txt) and is only called when the CPU has both.
#include "cpu/shadow_rays_kernel.h"

namespace scatterlab::shadow_detail {

float densitySumAvx2(const DensityLayout& g, const float u0[3], const float du[3], int n,
                     float sumMax) {
  return g.step[0] == 1 ? densitySum<xsimd::avx2, true>(g, u0, du, n, sumMax)
                        : densitySum<xsimd::avx2, false>(g, u0, du, n, sumMax);
}

}  // namespace scatterlab::shadow_detail
