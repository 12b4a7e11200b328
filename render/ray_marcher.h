#pragma once
/// The CPU ray marcher (the integrator stage): for each pixel, march the camera ray through the
/// medium box and sum in-scattering, front to back:
///   L += T · (σs/σt) · (1 − exp(−σt·D·Δt)) · S(x_mid),   T *= exp(−σt·D·Δt),
/// which is exact for D and S constant over each step; then L += T · background, and the
/// pixel's alpha is 1 − T (Image::alpha, for compositing).
/// `source(x, toViewer)` supplies S: traced (exact method) or looked up in a volume.

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include "core/image.h"
#include "core/progress.h"
#include "core/scene.h"
#include "core/stages.h"

namespace scatterlab {

template <class Source>
Image marchImage(const Scene& scene, const DensityGrid& density, const Source& source,
                 const MarchSettings& ms, Progress* progress) {
  const Camera& cam = scene.camera;
  const auto rays = cam.rayGenerator();
  const Medium& m = scene.medium;
  const float sigmaT = m.sigmaT, ratio = m.albedo;  // σs/σt = Ω
  Image img(cam.width, cam.height);
  img.alpha().assign(img.pixels().size(), 0.0f);
  tbb::parallel_for(tbb::blocked_range<int>(0, cam.height),
                    [&](const tbb::blocked_range<int>& rows) {
                      for (int y = rows.begin(); y < rows.end(); ++y) {
                        for (int x = 0; x < cam.width; ++x) {
                          const Ray r = rays(x, y);
                          Vec3 L(0.0f);
                          float T = 1.0f;
                          float t0, t1;
                          if (sigmaT > 0.0f && m.bounds.intersect(r, t0, t1) && t1 > t0) {
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
                          img.at(x, y) = L + T * scene.background;
                          img.alpha()[size_t(y) * cam.width + x] = 1.0f - T;
                        }
                        if (progress) progress->advance(1);
                      }
                    });
  return img;
}

}  // namespace scatterlab
