#pragma once
/// `light-space-march` on the CPU (Tóth & Umenhoffer 2009; docs/light-space-march.md): per
/// pixel, the view ray from the visible surface (or the medium box's far side) to the eye is cut
/// into N equal steps; term n is
///   T_n · Ω · (1 − e^(−σt·D_n·Δ)) · Σ_l E_l(x_n)·f(ω_l → ω)·v_l(x_n)·T_l(x_n),
/// T_n the view transmittance up to step n (all N densities are looked up), v_l the shadow-map
/// visibility (cpu/shadow_map.h: the maps of render.shadow_map with a depth compare; 1
/// without objects), T_l the light's transmittance,
/// e^(−σt·D̄·d) (D̄ the mean density, d the segment to the light inside the box) or traced.
/// Interleaved sampling (their Sec. 4.1): the image is covered by M×M blocks and pixel (x, y)
/// evaluates only the terms n ≡ (x mod M) + M·(y mod M) (mod M²); the image of these partial
/// sums is then summed over a sliding M×M window (a horizontal and a vertical pass), which
/// holds one pixel of every class. The boundary term T_N·L0 (background, or the surface's L_p
/// of shading/transport.h's SurfaceRadiance) is each pixel's own.

#include <memory>
#include <vector>

#include "core/image.h"
#include "core/progress.h"
#include "core/scene.h"
#include "core/stages.h"
#include "cpu/shadow_map.h"
#include "shading/post_process.h"

namespace scatterlab {

class LightSpaceMarcher {
 public:
  /// References must outlive this object. Builds the shadow maps (`shadowMap`'s resolution,
  /// bias and filter) when the scene has objects.
  LightSpaceMarcher(const Scene& scene, const DensityGrid& density,
                    const LightSpaceMarchSettings& settings, float delta1,
                    const ShadowMapSettings& shadowMap = {});

  /// One pixel's ray: the sum of its terms n = first, first + stride, ... (< N), and its
  /// boundary term and alpha (1 − T_N, or 1 on a surface).
  struct Pixel {
    Vec3 inScatter{0.0f};
    Vec3 boundary{0.0f};
    float alpha = 0.0f;
  };
  Pixel march(const Ray& r, int first, int stride) const;

  /// The image: every pixel's own terms (its interleaving class), block-summed, plus its
  /// boundary term. ConfigError when interleave exceeds the image or camera.spp > 1.
  Image render(Progress* progress) const;

  float meanDensity() const { return mean_; }

 private:
  /// The source term Σ_l E_l·f·v_l·T_l at x for light leaving towards the viewer.
  Vec3 source(const Vec3& x, const Vec3& toViewer) const;

  const Scene& scene_;
  const DensityGrid& density_;
  LightSpaceMarchSettings s_;
  float delta1_;
  float mean_ = 0.0f;
  std::unique_ptr<ShadowMap> shadows_;  ///< every light's; null without objects
};

/// The separable sliding-window sum of interleaved sampling: out(x, y) = Σ of `terms` over the
/// m×m window of blockWindowStart (shading/post_process.h) in x and y. RGB only.
Image blockSum(const Image& terms, int m);

/// Registers the CPU variant of integrator "light-space-march".
void registerLightSpaceMarch();

}  // namespace scatterlab
