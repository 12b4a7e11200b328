#pragma once
/// The GL variant of "radial-blur" (shading/post_process.h; the twin of cpu/radial_blur.cpp),
/// registered in gpu/register.cpp: compute passes over RGBA32F 2D images
/// (gpu/shaders/radial_blur.comp.glsl), read back once. Scene objects: the surface pass
/// (gpu/tracing.h ScreenSurfaces) gives the first surface of each pixel's ray and its L_p (the
/// occluders of the pre-pass). The host-data overload uploads the density, for tests that
/// compare with the CPU variant. Every member function needs a GL context (created on demand);
/// the constructor does not.

#include "core/stages.h"
#include "gpu/timer.h"
#include "gpu/volume.h"
#include "shading/post_process.h"

namespace scatterlab::gpu {

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
