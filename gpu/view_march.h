#pragma once
/// The compute view march (render.gpu_pipeline = compute, the default; docs/gpu.md): the GPU
/// "ray-marcher" integrator as one compute dispatch, one invocation per pixel, marching front to
/// back with early exit at min_transmittance and the CPU marcher's step placement
/// (cpu/ray_marcher.h marchWith: the same sample points, the same sums, camera.spp strata), so
/// that CPU ≡ GPU holds to float rounding. The paper's rasterised slice marcher
/// (gpu::SliceMarcher, render.gpu_pipeline = raster) stays beside it. Scene objects: their
/// surfaces are rasterised once (the surface pass of gpu/stages.h) and the march stops at
/// their distance and adds T·L_p. Steps inside blocks of zero density are jumped over
/// (gpu/empty_space.h; they add exactly 0). Needs the GL context for integrate().

#include <memory>

#include "core/stages.h"
#include "gpu/tracing.h"

namespace scatterlab::gpu {

class ViewMarchGpu : public Integrator {
 public:
  /// factorLights: the radiance volume holds V = S / A; A is multiplied back at each step.
  /// delta1: the step of the surfaces' T(p, l); shadowMap: their visibility lookups.
  /// lampModel: A includes LampModel's m_l (PipelineSettings::lampModel, with factorLights).
  ViewMarchGpu(MarchSettings settings, bool factorLights, float delta1, ShadowMapSettings shadowMap,
               bool lampModel = false)
      : settings_(settings),
        factor_(factorLights),
        lamp_(lampModel),
        delta1_(delta1),
        shadowMap_(shadowMap) {}
  Image integrate(Frame& frame, const Scene& scene, Progress* progress) override;
  /// gpu_pipeline "compute".
  void describe(RenderStats& stats) const override;
  /// The march over uploaded volumes (tests: CPU ≡ GPU).
  Image integrate(const Scene& scene, const DensityGrid& density, const RadianceGrid& radiance);
  /// The pass itself; GPU times "view march" and "read-back" into `timer` (may be null). With
  /// `keep`, the image stays in *keep (RGBA32F) and an empty Image is returned. With
  /// `counters`, it is made a GpuMarchCounters buffer the pass fills (steps looked up and
  /// jumped over; the frame's stats march_steps and march_steps_skipped).
  Image integrate(const Scene& scene, const Volume& density, const Volume& radiance,
                  StageTimer* timer, Texture* keep = nullptr, Buffer* counters = nullptr);
  /// Empty-space skipping (on by default; gpu/empty_space.h): the same image bit for bit, off
  /// only to measure it.
  void skipEmptySpace(bool on) { skipEmpty_ = on; }

 private:
  MarchSettings settings_;
  bool factor_;
  bool lamp_;
  float delta1_;
  ShadowMapSettings shadowMap_;
  bool skipEmpty_ = true;
  /// A's far field in the last integrate (stats far_field_terms, read after the frame): the
  /// vertices its passes computed, counted on the GPU (null: the grid was kept), and the
  /// point-light terms per counted vertex (every point light when built, the changed ones when
  /// updated: each of the two passes counts its vertices); −1 without a far field.
  std::shared_ptr<Buffer> farCounter_;
  long long farTermsPerVertex_ = -1;
};

}  // namespace scatterlab::gpu
