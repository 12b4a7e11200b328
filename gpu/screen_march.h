#pragma once
/// GL variants of the per-pixel competitors (docs/competitors.md), integrators behind the
/// interface of core/stages.h, registered in gpu/register.cpp beside the CPU ones of
/// cpu/integrators.cpp:
///   "jittered-march" — pass 1 marches every low-res pixel (jittered_march.comp.glsl), pass 2
///                      upsamples bilaterally and adds the background (jittered_upsample);
///   "froxel"         — optional per-light transmittance maps (froxel_map), then scatter and
///                      front-to-back accumulation per froxel column into an RGBA32F 3D image
///                      (froxel_scatter), then one lookup per pixel (froxel_lookup).
/// Scene objects: each pixel's ray ends at the surface pass's first surface (gpu/stages.h
/// ScreenSurfaces) and adds T·L_p there; the light's visibility at every sample is the shadow
/// maps' (gpu/shadow_maps.h, render.shadow_map), where the CPU variants trace Embree shadow
/// rays. Every member function needs a GL context (created on demand).

#include "core/stages.h"
#include "gpu/timer.h"
#include "gpu/volume.h"
#include "shading/screen_march.h"

namespace scatterlab::gpu {

class JitteredMarchGpu : public Integrator {
 public:
  explicit JitteredMarchGpu(const PipelineSettings& s)
      : s_(s.integratorKeys.get<JitteredMarchSettings>()),
        minT_(s.march.minTransmittance),
        delta1_(s.delta1),
        shadowMap_(s.shadowMap) {}
  bool needsRadiance() const override { return false; }
  Image integrate(Frame& frame, const Scene& scene, Progress* progress) override;
  void describe(RenderStats& stats) const override;
  /// The passes on an uploaded density volume.
  Image integrate(const Scene& scene, const Volume& density, StageTimer* timer);

 private:
  JitteredMarchSettings s_;
  float minT_, delta1_;
  ShadowMapSettings shadowMap_;
};

class FroxelGpu : public Integrator {
 public:
  explicit FroxelGpu(const PipelineSettings& s)
      : s_(s.integratorKeys.get<FroxelSettings>()),
        minT_(s.march.minTransmittance),
        delta1_(s.delta1),
        shadowMap_(s.shadowMap) {}
  bool needsRadiance() const override { return false; }
  Image integrate(Frame& frame, const Scene& scene, Progress* progress) override;
  void describe(RenderStats& stats) const override;
  Image integrate(const Scene& scene, const Volume& density, StageTimer* timer);

 private:
  FroxelSettings s_;
  float minT_, delta1_;
  ShadowMapSettings shadowMap_;
};

}  // namespace scatterlab::gpu
