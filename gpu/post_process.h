#pragma once
/// GL variants of the real-time methods' integrators (shading/post_process.h), registered in
/// gpu/register.cpp beside the CPU ones of cpu/: "light-space-march"
/// (gpu/shaders/light_space_march.comp.glsl, the twin of cpu/light_space_march.cpp) and
/// "radial-blur" (gpu/shaders/radial_blur.comp.glsl, the twin of cpu/radial_blur.cpp).
/// Compute passes over RGBA32F 2D images, read back once. Scene objects: the shadow maps of
/// gpu/shadow_maps.h (render.shadow_map) give light-space-march its v_l, and the surface pass
/// (gpu/stages.h ScreenSurfaces) the first surface of each pixel's ray and its L_p (where the
/// march ends, and the occluders of radial-blur's pre-pass). The host-data overloads
/// upload the density, for tests that compare with the CPU variants. Every member function
/// needs a GL context (created on demand); constructors do not.

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

class RadialBlurGpu : public Integrator {
 public:
  /// delta1: the step of T(p, l) for surfaces' L_p; shadowMap: their visibility lookups.
  RadialBlurGpu(RadialBlurSettings s, MarchSettings march, float delta1 = 0.0f,
                ShadowMapSettings shadowMap = {})
      : s_(s), march_(march), delta1_(delta1), shadowMap_(shadowMap) {}
  bool needsRadiance() const override { return false; }
  Image integrate(Frame& frame, const Scene& scene, Progress* progress) override;
  void describe(RenderStats& stats) const override;
  Image integrate(const Scene& scene, const DensityGrid& density);
  Image integrate(const Scene& scene, const Volume& density, StageTimer* timer);

 private:
  RadialBlurSettings s_;
  MarchSettings march_;
  float delta1_;
  ShadowMapSettings shadowMap_;
  Json positions_ = Json::array();
};

}  // namespace scatterlab::gpu
