#pragma once
/// The per-pixel composition shared by the screen-space methods (`froxel`, `jittered-march`):
/// each pixel's primary ray is intersected with the scene objects, the method supplies the
/// in-scattered radiance L and transmittance T in front of the first surface (or through the
/// whole medium), and the pixel becomes
///   no surface:  L + T·background,          alpha 1 − T;
///   surface:     L + T·L_surface (T > minT), alpha 1   (L alone once T ≤ minT),
/// with L_surface the surface's radiance (SurfaceRadiance: lights × visibility × the medium's
/// transmittance to each light).

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include "core/image.h"
#include "core/scene.h"
#include "shading/transport.h"

namespace scatterlab {

/// What a method returns for one pixel.
struct PixelMedium {
  Vec3 L{0.0f};
  float T = 1.0f;
};

/// Renders the image with `medium(x, y, ray, hit)` → PixelMedium, where `hit` is the first
/// surface along the ray or nullptr. Parallel over rows (TBB).
template <class MediumFn>
Image composeScreen(const Scene& scene, const DensityGrid& density, float delta1,
                    float minTransmittance, MediumFn&& medium) {
  const Camera& cam = scene.camera;
  const auto rays = cam.rayGenerator();
  const SurfaceRadiance surface(scene, density, delta1);
  Image img(cam.width, cam.height);
  img.alpha().assign(img.pixels().size(), 0.0f);
  tbb::parallel_for(tbb::blocked_range<int>(0, cam.height), [&](const tbb::blocked_range<int>& r) {
    for (int y = r.begin(); y < r.end(); ++y)
      for (int x = 0; x < cam.width; ++x) {
        const Ray ray = rays(x, y);
        SurfaceHit hit;
        const bool hasHit = scene.objects && scene.objects->intersect(ray, 0.0f, kInfinity, hit);
        const PixelMedium m = medium(x, y, ray, hasHit ? &hit : nullptr);
        const size_t p = size_t(y) * cam.width + x;
        if (!hasHit) {
          img.pixels()[p] = m.L + m.T * scene.background;
          img.alpha()[p] = 1.0f - m.T;
        } else {
          img.pixels()[p] = m.T > minTransmittance ? m.L + m.T * surface(hit) : m.L;
          img.alpha()[p] = 1.0f;
        }
      }
  });
  return img;
}

}  // namespace scatterlab
