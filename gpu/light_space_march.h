#pragma once
/// The GL variant of "light-space-march" (shading/post_process.h; the twin of
/// cpu/light_space_march.cpp), registered in gpu/register.cpp: compute passes over RGBA32F 2D
/// images (gpu/shaders/light_space_march.comp.glsl), read back once. Scene objects: the shadow
/// maps of gpu/shadow_maps.h (render.shadow_map) give it v_l, and the surface pass
/// (gpu/tracing.h ScreenSurfaces) the first surface of each pixel's ray and its L_p, where the
/// march ends. The host-data overload uploads the density, for tests that compare with the CPU
/// variant. Every member function needs a GL context (created on demand); the constructor does
/// not.

#include "core/stages.h"
#include "gpu/timer.h"
#include "gpu/volume.h"
#include "shading/post_process.h"

namespace scatterlab::gpu {

class LightSpaceMarchGpu : public Integrator {
 public:
  LightSpaceMarchGpu(LightSpaceMarchSettings s, float delta1, ShadowMapSettings shadowMap = {})
      : s_(s), delta1_(delta1), shadowMap_(shadowMap) {}
  bool needsRadiance() const override { return false; }
  Image integrate(Frame& frame, const Scene& scene, Progress* progress) override;
  void describe(RenderStats& stats) const override;
  Image integrate(const Scene& scene, const DensityGrid& density);
  /// `meanDensity`: D̄ of the density (used with light_transmittance "mean").
  Image integrate(const Scene& scene, const Volume& density, float meanDensity, StageTimer* timer);

 private:
  LightSpaceMarchSettings s_;
  float delta1_;
  ShadowMapSettings shadowMap_;
  float mean_ = 0.0f;
  int shadowMaps_ = 0;
};

}  // namespace scatterlab::gpu
