#include "cpu/jittered_march.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include "cpu/screen_compose.h"
#include "shading/screen_march.h"
#include "shading/transport.h"

namespace scatterlab {

Ray lowResRay(const Camera::RayGenerator& rays, int d, int i, int j) {
  return rays.at((float(i) + 0.5f) * float(d), (float(j) + 0.5f) * float(d));
}

LowResMarch jitteredMarchLowRes(const Scene& scene, const DensityGrid& density,
                                const JitteredMarchSettings& s, const MarchSettings& ms,
                                float delta1, Progress* progress) {
  const Camera& cam = scene.camera;
  const auto rays = cam.rayGenerator();
  const Medium& m = scene.medium;
  const float sigmaT = m.sigmaT, ratio = m.albedo;
  const SourceRadiance source(scene, density, delta1);
  LowResMarch low;
  low.downsample = s.downsample;
  low.width = (cam.width + s.downsample - 1) / s.downsample;
  low.height = (cam.height + s.downsample - 1) / s.downsample;
  const size_t n = size_t(low.width) * low.height;
  low.L.assign(n, Vec3(0.0f));
  low.T.assign(n, 1.0f);
  low.depth.assign(n, kInfinity);
  if (progress) progress->restart("march", low.height);
  tbb::parallel_for(tbb::blocked_range<int>(0, low.height), [&](const tbb::blocked_range<int>& r) {
    for (int j = r.begin(); j < r.end(); ++j) {
      for (int i = 0; i < low.width; ++i) {
        const Ray ray = lowResRay(rays, s.downsample, i, j);
        const size_t p = size_t(j) * low.width + i;
        SurfaceHit hit;
        const bool hasHit = scene.objects && scene.objects->intersect(ray, 0.0f, kInfinity, hit);
        float t0, t1;
        const bool inBox = m.bounds.intersect(ray, t0, t1) && t1 > t0;
        low.depth[p] = hasHit ? hit.t : inBox ? t1 : kInfinity;
        if (!inBox || sigmaT <= 0.0f) continue;
        if (hasHit) t1 = std::min(t1, hit.t);
        if (!(t1 > t0)) continue;
        const float dt = (t1 - t0) / float(s.steps);
        const float o = jitterOffset(s.jitter, i, j);
        const Vec3 sc = density.indexScale();
        const Vec3 u0 = ray.at(t0 + o * dt) * sc + density.indexOffset();
        const Vec3 du = ray.dir * dt * sc;
        Vec3 L(0.0f);
        float T = 1.0f;
        for (int k = 0; k < s.steps && T > ms.minTransmittance; ++k) {
          const float D = density.sampleIndex(u0 + float(k) * du);
          if (D <= 0.0f) continue;
          const float a = std::exp(-sigmaT * D * dt);
          L += (T * ratio * (1.0f - a)) * source(ray.at(t0 + (float(k) + o) * dt), -ray.dir);
          T *= a;
        }
        low.L[p] = L;
        low.T[p] = T;
      }
      if (progress) progress->advance(1);
    }
  });
  return low;
}

void upsampleWeights(const LowResMarch& low, int x, int y, float depth, int idx[4], float w[4]) {
  const float d = float(low.downsample);
  const float lx = (float(x) + 0.5f) / d - 0.5f, ly = (float(y) + 0.5f) / d - 0.5f;
  const int i0 = std::clamp(int(std::floor(lx)), 0, low.width - 1);
  const int j0 = std::clamp(int(std::floor(ly)), 0, low.height - 1);
  const int i1 = std::min(i0 + 1, low.width - 1), j1 = std::min(j0 + 1, low.height - 1);
  const float fx = std::clamp(lx - float(i0), 0.0f, 1.0f);
  const float fy = std::clamp(ly - float(j0), 0.0f, 1.0f);
  idx[0] = j0 * low.width + i0;
  idx[1] = j0 * low.width + i1;
  idx[2] = j1 * low.width + i0;
  idx[3] = j1 * low.width + i1;
  const float b[4] = {(1 - fx) * (1 - fy), fx * (1 - fy), (1 - fx) * fy, fx * fy};
  float sum = 0.0f;
  int nearest = 0;
  float nearestDiff = kInfinity;
  for (int c = 0; c < 4; ++c) {
    const float di = low.depth[idx[c]];
    // Equal depths (both +∞ included) weigh 1; one finite and one infinite weigh 0.
    const float diff = di == depth ? 0.0f : std::abs(di - depth);
    const float sim = diff == 0.0f        ? 1.0f
                      : std::isinf(diff)  ? 0.0f
                      : std::isinf(depth) ? 0.0f
                                          : std::exp(-diff / (kUpsampleDepthSigma * depth));
    w[c] = b[c] * sim;
    sum += w[c];
    if (diff < nearestDiff) {
      nearestDiff = diff;
      nearest = c;
    }
  }
  if (sum < 1e-6f) {
    for (int c = 0; c < 4; ++c) w[c] = c == nearest ? 1.0f : 0.0f;
    return;
  }
  for (int c = 0; c < 4; ++c) w[c] /= sum;
}

Image jitteredMarch(const Scene& scene, const DensityGrid& density, const JitteredMarchSettings& s,
                    const MarchSettings& ms, float delta1, Progress* progress) {
  const LowResMarch low = jitteredMarchLowRes(scene, density, s, ms, delta1, progress);
  return composeScreen(scene, density, delta1, ms.minTransmittance,
                       [&](int x, int y, const Ray& ray, const SurfaceHit* hit) {
                         float t0, t1;
                         const float depth = hit ? hit->t
                                             : scene.medium.bounds.intersect(ray, t0, t1) && t1 > t0
                                                 ? t1
                                                 : kInfinity;
                         int idx[4];
                         float w[4];
                         upsampleWeights(low, x, y, depth, idx, w);
                         PixelMedium m;
                         m.T = 0.0f;
                         for (int c = 0; c < 4; ++c) {
                           m.L += w[c] * low.L[idx[c]];
                           m.T += w[c] * low.T[idx[c]];
                         }
                         return m;
                       });
}

}  // namespace scatterlab
