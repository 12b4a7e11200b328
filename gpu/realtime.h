#pragma once
/// GL variants of the real-time methods' integrators (core/realtime.h), registered in
/// gpu/register.cpp beside the CPU ones of render/: "light-space-march"
/// (gpu/shaders/light_space_march.comp.glsl, the twin of render/light_space_march.cpp) and
/// "radial-blur" (gpu/shaders/radial_blur.comp.glsl, the twin of render/radial_blur.cpp).
/// Compute passes over RGBA32F 2D images, read back once. Scenes with objects are refused with a
/// ConfigError (no GPU shadow maps yet: the visibility of every sample point is 1 in the
/// shader's lightVisibility, where the shadow-map lookup slots in). The host-data overloads
/// upload the density, for tests that compare with the CPU variants. Every member function
/// needs a GL context (created on demand); constructors do not.

#include "core/realtime.h"
#include "core/stages.h"
#include "gpu/timer.h"
#include "gpu/volume.h"

namespace scatterlab::gpu {

class LightSpaceMarchGpu : public Integrator {
 public:
  LightSpaceMarchGpu(LightSpaceMarchSettings s, float delta1) : s_(s), delta1_(delta1) {}
  bool needsRadiance() const override { return false; }
  Image integrate(Frame& frame, const Scene& scene, Progress* progress) override;
  void describe(RenderStats& stats) const override;
  Image integrate(const Scene& scene, const DensityGrid& density);
  /// `meanDensity`: D̄ of the density (used with light_transmittance "mean").
  Image integrate(const Scene& scene, const Volume& density, float meanDensity, StageTimer* timer);

 private:
  LightSpaceMarchSettings s_;
  float delta1_;
  float mean_ = 0.0f;
};

class RadialBlurGpu : public Integrator {
 public:
  RadialBlurGpu(RadialBlurSettings s, MarchSettings march) : s_(s), march_(march) {}
  bool needsRadiance() const override { return false; }
  Image integrate(Frame& frame, const Scene& scene, Progress* progress) override;
  void describe(RenderStats& stats) const override;
  Image integrate(const Scene& scene, const DensityGrid& density);
  Image integrate(const Scene& scene, const Volume& density, StageTimer* timer);

 private:
  RadialBlurSettings s_;
  MarchSettings march_;
  Json positions_ = Json::array();
};

}  // namespace scatterlab::gpu
