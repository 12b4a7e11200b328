#pragma once
/// The paper's slice marcher (Sec. 6), integrator "ray-marcher" of the raster pipeline
/// (DESIGN.md §3), registered in gpu/register.cpp.

#include "core/stages.h"
#include "gpu/shadow_maps.h"
#include "gpu/timer.h"
#include "gpu/tracing.h"
#include "gpu/volume.h"

namespace scatterlab::gpu {

/// Slice-based ray marching (paper Sec. 6): slabs of view depth perpendicular to the camera's
/// forward axis, thickness `settings.step`, drawn far to near with blending
/// GL_ONE / GL_SRC_ALPHA; per pixel each slab's piece of the ray, clipped to the box, is one
/// step of the CPU marcher's formula (rgb = Ω(1 − a)S, a = exp(−σt·D·Δt)), and the framebuffer
/// starts as the background. minTransmittance is not used (there is no early exit).
/// With `raySteps`, layer k is instead step n−1−k of each pixel's own ray (the CPU marcher's
/// sample points exactly, composited the same way): it matches the CPU image where the planar
/// slabs' different sample points matter (a point light inside the medium).
/// Scene objects: a first pass rasterises them from the camera with a depth buffer into the
/// framebuffer: their L_p = albedo/π·Σ_l E_l·max(0, n·ω_l)·V_l·T(p, l) per pixel (V_l from the
/// shadow maps, T marched through the density with step delta1), alpha 0 (opaque), and their
/// view-ray distance into a second attachment. The layers then composite over it: view-plane
/// slabs entirely behind the surface fail the depth test (culled), and every layer's piece of
/// a ray is clipped at the surface, as the CPU march stops there; T(camera, p)·L_p follows
/// from the blending.
class SliceMarcher : public Integrator {
 public:
  /// factorLights: the radiance volume holds V = S / A; A is multiplied back per layer.
  /// delta1: the step of T(p, l) for surfaces; shadowMap: their visibility lookups.
  /// lampModel: A includes LampModel's m_l (PipelineSettings::lampModel, with factorLights).
  explicit SliceMarcher(MarchSettings settings, bool raySteps = false, bool factorLights = false,
                        float delta1 = 0.0f, ShadowMapSettings shadowMap = {},
                        bool lampModel = false)
      : settings_(settings),
        raySteps_(raySteps),
        factor_(factorLights),
        lamp_(lampModel),
        delta1_(delta1),
        shadowMap_(shadowMap) {}
  Image integrate(Frame& frame, const Scene& scene, Progress* progress) override;
  /// slicing and the number of slices of the last integrate().
  void describe(RenderStats& stats) const override;
  /// `objects`: the scene's objects and shadow maps (null or empty without objects).
  Image integrate(const Scene& scene, const Volume& density, const Volume& radiance,
                  StageTimer* timer, int* slices = nullptr, const SceneShadows* objects = nullptr);

 private:
  MarchSettings settings_;
  bool raySteps_;
  bool factor_;
  bool lamp_;
  float delta1_;
  ShadowMapSettings shadowMap_;
  int slices_ = 0;
};

}  // namespace scatterlab::gpu
