#pragma once
/// `jittered-march` on the CPU (docs/competitors.md; the ray-marching write-ups, Bevy and Unity
/// practice): every (low-resolution) pixel marches its camera ray through the medium box, up
/// to the first surface, in a fixed number N of steps whatever the ray's length,
///   Δt = (t1 − t0)/N,  x_k = t0 + (k + o)·Δt,  o = jitterOffset(jitter, pixel) ∈ [0, 1),
///   L += T·Ω·(1 − e^(−σt·D·Δt))·S(x_k),  T *= e^(−σt·D·Δt),
/// with S traced to every light at every sample (step delta1; exact but coarse in N). At
/// downsample > 1 the march runs at ⌈W/d⌉ × ⌈H/d⌉ rays through the centres of d × d blocks and
/// is upsampled with bilateral weights (bilinear × depth similarity, upsampleWeights), then each
/// full-resolution pixel adds T·(its own surface radiance or the background).

#include <memory>
#include <vector>

#include "core/image.h"
#include "core/progress.h"
#include "core/scene.h"
#include "core/stages.h"
#include "shading/screen_march.h"

namespace scatterlab {

/// The march at low resolution: in-scattered radiance L, transmittance T, and the depth (ray
/// distance) where each ray's march ended (the first surface, the box exit, or +∞ for a ray
/// that misses the box).
struct LowResMarch {
  int width = 0, height = 0, downsample = 1;
  std::vector<Vec3> L;
  std::vector<float> T, depth;
};

/// The four bilateral weights of full-resolution pixel (x, y) at `depth` over the low-res
/// pixels (i0, j0), (i1, j0), (i0, j1), (i1, j1) (returned in `idx`): bilinear weights of the
/// pixel centre among the block centres times e^(−|d_i − d| / (kUpsampleDepthSigma·d))
/// (shading/screen_march.h); when
/// every product is below 1e-6, all weight goes to the neighbour of nearest depth. They sum
/// to 1. At downsample 1 the pixel's own low-res pixel has weight 1.
void upsampleWeights(const LowResMarch& low, int x, int y, float depth, int idx[4], float w[4]);

/// The march ray of low-res pixel (i, j): through full-res image coordinates ((i + ½)·d,
/// (j + ½)·d).
Ray lowResRay(const Camera::RayGenerator& rays, int downsample, int i, int j);

/// Runs the low-res march.
LowResMarch jitteredMarchLowRes(const Scene& scene, const DensityGrid& density,
                                const JitteredMarchSettings& s, const MarchSettings& ms,
                                float delta1, Progress* progress);

/// The whole method: low-res march, upsampling, surfaces/background at full resolution.
Image jitteredMarch(const Scene& scene, const DensityGrid& density, const JitteredMarchSettings& s,
                    const MarchSettings& ms, float delta1, Progress* progress);

}  // namespace scatterlab
