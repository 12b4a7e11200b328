#pragma once
/// The CPU ray marcher (the integrator stage): for each pixel, march the camera ray through the
/// medium box and sum in-scattering, front to back:
///   L += T · (σs/σt) · (1 − exp(−σt·D·Δt)) · S(x_mid),   T *= exp(−σt·D·Δt),
/// which is exact for D and S constant over each step; then L += T · background, and the
/// pixel's alpha is 1 − T (Image::alpha, for compositing).
/// `source(x, toViewer)` supplies S: traced (exact method) or looked up in a volume.
/// With scene objects, the march stops at the first surface and adds T·L_p (SurfaceRadiance,
/// traced per pixel with step `surfaceDelta1`) instead of T·background, and alpha is 1 (the
/// surface is opaque). camera.spp > 1
/// averages k x k rays (radiance and alpha) through the stratum centres of each pixel.

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include "core/image.h"
#include "core/progress.h"
#include "core/scene.h"
#include "core/stages.h"
#include "core/transport.h"

namespace scatterlab {

template <class Source>
Image marchImage(const Scene& scene, const DensityGrid& density, const Source& source,
                 const MarchSettings& ms, Progress* progress, float surfaceDelta1 = 0.0f) {
  const Camera& cam = scene.camera;
  const auto rays = cam.rayGenerator();
  const Medium& m = scene.medium;
  const float sigmaT = m.sigmaT, ratio = m.albedo;  // σs/σt = Ω
  const SceneObjects* objects = scene.objects.get();
  const SurfaceRadiance surface(scene, density, surfaceDelta1 > 0.0f ? surfaceDelta1 : ms.step);
  // One camera ray: in-scattering up to the first surface (or the box exit), then T·L_p of
  // the surface or T·background.
  // Radiance and alpha: 1 − T of the medium, 1 where an (opaque) surface is hit.
  struct Shaded {
    Vec3 L;
    float alpha;
  };
  const auto radiance = [&](const Ray& r) -> Shaded {
    Vec3 L(0.0f);
    float T = 1.0f;
    SurfaceHit hit;
    const bool hasHit = objects && objects->intersect(r, 0.0f, kInfinity, hit);
    float t0, t1;
    if (sigmaT > 0.0f && m.bounds.intersect(r, t0, t1) && t1 > t0) {
      if (hasHit) t1 = std::min(t1, hit.t);
      if (t1 > t0) {
        const int n = std::max(1, int(std::ceil((t1 - t0) / ms.step)));
        const float dt = (t1 - t0) / float(n);
        const Vec3 s = density.indexScale();
        const Vec3 u0 = r.at(t0 + 0.5f * dt) * s + density.indexOffset();
        const Vec3 du = r.dir * dt * s;
        for (int i = 0; i < n && T > ms.minTransmittance; ++i) {
          const float D = density.sampleIndex(u0 + float(i) * du);
          if (D <= 0.0f) continue;
          const float a = std::exp(-sigmaT * D * dt);
          const Vec3 p = r.at(t0 + (float(i) + 0.5f) * dt);
          L += (T * ratio * (1.0f - a)) * source(p, -r.dir);
          T *= a;
        }
      }
    }
    if (!hasHit) return {L + T * scene.background, 1.0f - T};
    // Below min_transmittance the surface's share is below it too (as for the medium).
    return {T > ms.minTransmittance ? L + T * surface(hit) : L, 1.0f};
  };
  const int k = std::max(1, int(std::lround(std::sqrt(double(cam.spp)))));
  const float inv = 1.0f / float(k * k);
  Image img(cam.width, cam.height);
  img.alpha().assign(img.pixels().size(), 0.0f);
  tbb::parallel_for(
      tbb::blocked_range<int>(0, cam.height), [&](const tbb::blocked_range<int>& rows) {
        for (int y = rows.begin(); y < rows.end(); ++y) {
          for (int x = 0; x < cam.width; ++x) {
            if (k == 1) {
              const Shaded sh = radiance(rays(x, y));
              img.at(x, y) = sh.L;
              img.alpha()[size_t(y) * cam.width + x] = sh.alpha;
              continue;
            }
            // k x k stratum centres, box filter.
            Vec3 sum(0.0f);
            float alpha = 0.0f;
            for (int j = 0; j < k; ++j)
              for (int i = 0; i < k; ++i) {
                const Shaded sh = radiance(rays.at(float(x) + (float(i) + 0.5f) / float(k),
                                                   float(y) + (float(j) + 0.5f) / float(k)));
                sum += sh.L;
                alpha += sh.alpha;
              }
            img.at(x, y) = sum * inv;
            img.alpha()[size_t(y) * cam.width + x] = alpha * inv;
          }
          if (progress) progress->advance(1);
        }
      });
  return img;
}

}  // namespace scatterlab
