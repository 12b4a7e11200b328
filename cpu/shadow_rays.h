#pragma once
/// Shadow rays of the `exact` integrator with SIMD over their steps (issue 14): lane l of a
/// batch takes step i + l of the same ray, so each trilinear lookup's index arithmetic and
/// interpolation are done for 4 (SSE2, the baseline build) or 8 (AVX2 + FMA, chosen at run
/// time when the CPU has them) steps at once and the 8 corner reads are gathers. The same
/// steps as shading/transport.h's opticalDepth with a cutoff; only the order of the float sum
/// differs (and, with FMA, the rounding of u = u0 + i·du), so the result differs from the
/// scalar one by a few ulps of the sum.

#include <cstdint>

#include "core/grid.h"
#include "shading/transport.h"

namespace scatterlab {

/// A DensityGrid's data and the constants of Grid3::sampleIndex, as plain numbers.
struct DensityLayout {
  const float* data = nullptr;
  float maxIndex[3] = {0, 0, 0};
  std::int32_t maxBase[3] = {0, 0, 0};
  std::int32_t step[3] = {0, 0, 0};  ///< neighbour offsets (0 along an axis of one voxel)
  std::int32_t rowStride = 0, sliceStride = 0;
};
DensityLayout densityLayout(const DensityGrid& g);

/// The SIMD kernels: Sse2 (4 lanes, any x86-64) and Avx2 (8 lanes; only where shadowRayKernel()
/// says "avx2"); Best is the one the CPU runs fastest.
enum class ShadowKernel { Best, Sse2, Avx2 };

/// opticalDepth(g, a, b, step, maxDepth) of shading/transport.h (the same steps; the cutoff is
/// checked every 32 steps instead of 8, so a stopped ray may sum a few more) with the SIMD sum.
/// `layout` is densityLayout(g).
float opticalDepthSimd(const DensityGrid& g, const DensityLayout& layout, const Vec3& a,
                       const Vec3& b, float step, float maxDepth,
                       ShadowKernel kernel = ShadowKernel::Best);

/// opticalDepthSimd over one density volume as SourceRadiance's shadow-ray tracer. Must
/// outlive the SourceRadiance it is given to; `density` must outlive it.
class SimdShadowRays {
 public:
  explicit SimdShadowRays(const DensityGrid& density)
      : density_(density), layout_(densityLayout(density)) {}
  ShadowDepthFn fn() const { return {&trampoline, this}; }

 private:
  static float trampoline(const void* self, const Vec3& a, const Vec3& b, float step,
                          float maxDepth) {
    const auto* s = static_cast<const SimdShadowRays*>(self);
    return opticalDepthSimd(s->density_, s->layout_, a, b, step, maxDepth);
  }
  const DensityGrid& density_;
  DensityLayout layout_;
};

/// Which kernel opticalDepthSimd runs on this CPU: "avx2" or "sse2".
const char* shadowRayKernel();

}  // namespace scatterlab
