#pragma once
/// The GPU reconstructions "gradient" (radiance splatting, paper Sec. 4) and "per-voxel"
/// (DESIGN.md §3), registered in gpu/register.cpp. The interface overrides work in a GpuFrame
/// (gpu/frame.h); the Volume overloads are the passes.

#include <optional>
#include <span>

#include "core/stages.h"
#include "gpu/device_samples.h"
#include "gpu/shadow_maps.h"
#include "gpu/timer.h"
#include "gpu/volume.h"

namespace scatterlab::gpu {

/// Radiance splatting (paper Sec. 4, Eq. 4): every voxel centre x sums
/// (W·(S_j + (x − x_j)·∇S_j), W), W = R_j/‖x − x_j‖, over the samples whose valid sphere holds
/// it, into an RGBA32F volume; then a compute pass normalises into the source-radiance volume.
/// Voxels no sphere covers get S = 0. GpuPipeline::Compute gathers per voxel from the samples
/// binned on the host (gpu/sphere_bins.h, radiance_gather.comp.glsl); GpuPipeline::Raster is the
/// paper's splat: for each z slice, one quad per sample bounding its valid sphere's cut,
/// blended into the slice. Both sum in sample order.
class GradientSplatGpu : public Reconstruction {
 public:
  /// logSpace: the samples hold ln V; the normalised result is exponentiated. occlusion: the
  /// weights are multiplied by exp(−σt·τ) of the segment sample → voxel (set σt with
  /// setOcclusion, or through the frame override, which takes it from the scene).
  /// bounds: each sample's Taylor estimate is clamped to it (PipelineSettings::boundedTaylor).
  /// lamp: the values are V with LampModel; the bounds' hi is tightened per frame
  /// (lampBounds, shading/transport.h) as the CPU gather does.
  /// factored: the values are V = S / A with TracerSteps::reach: the compute gather leaves the
  /// voxels no spot cone reaches at 0 (LitReach), as the CPU gather.
  explicit GradientSplatGpu(bool logSpace = false, bool occlusion = false,
                            std::optional<TaylorBounds> bounds = std::nullopt,
                            GpuPipeline pipeline = GpuPipeline::Compute, bool lamp = false,
                            bool factored = false)
      : log_(logSpace),
        occlusion_(occlusion),
        lamp_(lamp),
        factored_(factored),
        bounds_(bounds),
        settingsBounds_(bounds),
        pipeline_(pipeline) {}
  bool needsGradients() const override { return true; }
  /// In a GpuFrame: gathers the frame's resident samples; uncovered_voxels reaches the stats
  /// through the frame's report (read after the frame), not the returned stats.
  ReconstructionStats reconstruct(Frame& frame, const Scene& scene,
                                  std::span<const RadianceSample> samples, IVec3 dims,
                                  Progress* progress) override;
  /// Splats into a new volume over `bounds` with `dims`. `resident`: the frame's samples on the
  /// GPU; the compute gather reads them where the tracer left them when they hold this
  /// render's S and ∇S for `samples` (else it uploads `samples` into them). `uncoveredCount`:
  /// receives the GPU counter of uncovered voxels instead of reading it into `stats` (a read
  /// that would wait for the GPU).
  Volume reconstruct(const Volume& density, std::span<const RadianceSample> samples,
                     const Box& bounds, IVec3 dims, ReconstructionStats* stats, StageTimer* timer,
                     DeviceSamples* resident = nullptr, Buffer* uncoveredCount = nullptr);

 private:
  bool log_, occlusion_, lamp_, factored_;
  std::optional<TaylorBounds> bounds_;          ///< this frame's (tightened with lamp_)
  std::optional<TaylorBounds> settingsBounds_;  ///< taylorBounds() of the settings
  /// The compute gather tightens bounds_'s hi for the lamps on the GPU (SL_LAMP_BOUNDS) from
  /// this scene's lights: set by the frame override for one call.
  const Scene* lampScene_ = nullptr;
  /// With factored_ (compute gather): the scene whose spot cones bound the voxels gathered
  /// (SL_LIT_REACH), set by the frame override for one call.
  const Scene* litScene_ = nullptr;
  GpuPipeline pipeline_;
  float sigmaT_ = 0.0f;  ///< for the occlusion weights
};

/// The per-voxel baseline on the GPU (twin of buildPerVoxelRadiance): S traced at every voxel
/// centre in one compute dispatch, empty neighbourhoods skipped. As a Reconstruction it
/// ignores the samples.
class PerVoxelGpu : public Reconstruction {
 public:
  /// `factored`, `lampModel`: the volume holds V = S / A (sourceTowardsEye with
  /// SL_FACTOR_LIGHTS), as the CPU's buildPerVoxelRadiance.
  explicit PerVoxelGpu(float delta1, ShadowMapSettings shadowMap = {}, bool factored = false,
                       bool lampModel = false)
      : delta1_(delta1), shadowMap_(shadowMap), factored_(factored), lampModel_(lampModel) {}
  bool needsGradients() const override { return false; }
  bool usesSamples() const override { return false; }
  ReconstructionStats reconstruct(Frame& frame, const Scene& scene,
                                  std::span<const RadianceSample> samples, IVec3 dims,
                                  Progress* progress) override;
  /// `stats` receives traced and skipped, or `countersOut` the GPU counters
  /// (GpuPerVoxelCounters) unread; `shadows`: the objects' shadow maps (or null).
  Volume build(const Scene& scene, const Volume& density, const Box& bounds, IVec3 dims,
               ReconstructionStats* stats, StageTimer* timer, const ShadowMaps* shadows = nullptr,
               Buffer* countersOut = nullptr);

 private:
  float delta1_;
  ShadowMapSettings shadowMap_;
  bool factored_, lampModel_;
};

}  // namespace scatterlab::gpu
