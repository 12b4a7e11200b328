#include "cpu/shadow_rays.h"

#include "core/cpu_features.h"
#include "cpu/shadow_rays_kernel.h"

namespace scatterlab {

namespace shadow_detail {
#ifdef SCATTERLAB_SHADOW_AVX2
float densitySumAvx2(const DensityLayout& g, const float u0[3], const float du[3], int n,
                     float sumMax);
#endif
}  // namespace shadow_detail

namespace {

using SumFn = float (*)(const DensityLayout&, const float*, const float*, int, float);

SumFn chooseKernel() {
#ifdef SCATTERLAB_SHADOW_AVX2
  if (cpuFeatures().avx2 && cpuFeatures().fma) return &shadow_detail::densitySumAvx2;
#endif
  return &shadow_detail::densitySum<xsimd::sse2>;
}

const SumFn kSum = chooseKernel();

}  // namespace

DensityLayout densityLayout(const DensityGrid& g) {
  DensityLayout l;
  const IVec3 n = g.dims();
  l.data = g.data().data();
  for (int a = 0; a < 3; ++a) {
    l.maxIndex[a] = float(n[a] - 1);
    l.maxBase[a] = std::max(n[a] - 2, 0);
  }
  l.rowStride = n.x;
  l.sliceStride = n.x * n.y;
  l.step[0] = n.x > 1 ? 1 : 0;
  l.step[1] = n.y > 1 ? n.x : 0;
  l.step[2] = n.z > 1 ? n.x * n.y : 0;
  return l;
}

float opticalDepthSimd(const DensityGrid& g, const DensityLayout& layout, const Vec3& a,
                       const Vec3& b, float step, float maxDepth, ShadowKernel kernel) {
  // The steps of opticalDepth (shading/transport.h), the box clip skipped when both ends lie in
  // the box (a view step and the box exit towards a directional light).
  const IndexSteps st = indexSteps(g, a, b, step, /*clipInside=*/false);
  if (st.n == 0) return 0.0f;
  const int n = st.n;
  const float dt = st.dt;
  const Vec3 u0 = st.u0, du = st.du;
  const float uu[3] = {u0.x, u0.y, u0.z}, dd[3] = {du.x, du.y, du.z};
  SumFn sum = kSum;
  if (kernel == ShadowKernel::Sse2) sum = &shadow_detail::densitySum<xsimd::sse2>;
#ifdef SCATTERLAB_SHADOW_AVX2
  if (kernel == ShadowKernel::Avx2) sum = &shadow_detail::densitySumAvx2;
#endif
  return sum(layout, uu, dd, n, maxDepth / dt) * dt;
}

const char* shadowRayKernel() {
#ifdef SCATTERLAB_SHADOW_AVX2
  if (kSum == &shadow_detail::densitySumAvx2) return "avx2";
#endif
  return "sse2";
}

}  // namespace scatterlab
