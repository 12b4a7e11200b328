#pragma once
/// GL variants of the pipeline stages (DESIGN.md §3), behind the interfaces of core/stages.h
/// and registered in gpu/register.cpp as the GPU variants beside the CPU ones: radiance
/// evaluator "volume-tracer", reconstructions "gradient" and "per-voxel", integrator
/// "ray-marcher" (the slice marcher).
/// The interface overrides work in a GpuFrame (gpu/frame.h; data stays on the GPU); the
/// host-data overloads upload and read back, for tests that compare with the CPU variants;
/// the Volume overloads are the passes themselves. Every member function needs a GL context
/// (gpu::context(), created on demand); constructors do not.

#include <span>

#include "core/stages.h"
#include "gpu/shadow_maps.h"
#include "gpu/timer.h"
#include "gpu/volume.h"

namespace scatterlab::gpu {

/// Buffers and uniforms every tracing shader (common.glsl) needs: the lights SSBO
/// (binding::kLights), the density texture (binding::kDensityTexture), phase, σt, Δ1, eye. Needs
/// a current context.
class TracingInputs {
 public:
  /// `shadows`: the scene objects' shadow maps (null without objects); programs that trace
  /// with these inputs must then be built with addShadowVariant(shadows(), ...).
  TracingInputs(const Scene& scene, const Volume& density, float delta1,
                const ShadowMaps* shadows = nullptr);
  /// Binds the buffers and texture and sets the uniforms of `program` (which must be in use).
  void apply(const Program& program) const;
  const ShadowMaps* shadows() const { return shadows_; }

 private:
  const Scene& scene_;
  const Volume& density_;
  float delta1_;
  const ShadowMaps* shadows_;
  Buffer lights_;
};

/// The scene objects on the GPU for one frame: their triangles and shadow maps (both null
/// without objects). Built once per render by the first stage that needs them.
struct SceneShadows {
  std::unique_ptr<ObjectGeometry> geometry;
  std::unique_ptr<ShadowMaps> maps;
  /// Uploads the objects and renders the maps when the scene has objects and they are not
  /// built yet; returns maps (null without objects). Needs the context.
  const ShadowMaps* build(const Scene& scene, const ShadowMapSettings& settings, StageTimer* timer);
};

/// The surface pass (docs/objects.md "GPU"): the scene's objects rasterised from the camera
/// with a depth buffer (surface.frag.glsl). Per pixel, the first surface's
/// L_p = albedo/π·Σ_l E_l·max(0, n·ω_l)·V_l·T(p, l) (V_l from the shadow maps, T marched with
/// the step of `inputs`) goes into the rgb of `color` (RGBA32F, the camera's size) with alpha 0,
/// after `color` was cleared to (background, 1); its view-ray distance goes into `distance`
/// (R32F, 3e38 where no surface), and its depth into `depth` (the depth range nearD..farD of
/// the camera's projection). The slice marcher composites over `color` with `depth` as its
/// depth buffer; the per-pixel methods (gpu/post_process.h, gpu/screen_march.h) read `distance`
/// and `color` (ScreenSurfaces). Needs the context, `objects` built and `inputs` made with its
/// maps.
struct SurfacePass {
  Texture distance;
  Texture depth;
  float nearD = 1.0f, farD = 2.0f;
};
SurfacePass renderSurfaces(const Scene& scene, const SceneShadows& objects,
                           const TracingInputs& inputs, const Texture& color, StageTimer* timer);

/// The surface pass as the per-pixel methods read it (built only when the scene has objects):
/// its L_p image and distances, bound at binding::kSurfaceRadianceTexture and
/// binding::kSurfaceTexture (the samplers uSurfaceRadiance and uSurfaceDistance of shaders
/// compiled with SL_OBJECTS: light_space_march, radial_blur, screen_common).
struct ScreenSurfaces {
  Texture radiance;
  SurfacePass pass;
  bool built = false;
  /// Runs the surface pass when `objects` has maps (the scene has objects), else does nothing.
  void build(const Scene& scene, const SceneShadows& objects, const TracingInputs& inputs,
             StageTimer* timer);
  /// Binds the two textures (when built).
  void bind() const;
};

/// S and ∇S at every sample in one compute dispatch (GPU twin of the CPU volume tracer):
/// S(x) = SourceRadiance(x, towards the camera position), ∇S by central differences with step
/// delta2 along each world axis, each offset point with its own view direction.
class VolumeTracerGpu : public RadianceEvaluator {
 public:
  /// steps: tracing and central-difference steps (world units), and whether V = S / A (or
  /// ln V) is evaluated instead of S, as the CPU evaluator does (PipelineSettings).
  /// shadowMap: how scene objects' visibility is looked up (render.shadow_map).
  explicit VolumeTracerGpu(TracerSteps steps, ShadowMapSettings shadowMap = {})
      : delta1_(steps.delta1),
        delta2_(steps.delta2),
        factor_(steps.factorLights),
        log_(steps.logValues()),
        lamp_(steps.lampModel),
        shadowMap_(shadowMap) {}
  void evaluate(Frame& frame, const Scene& scene, std::span<RadianceSample> samples,
                bool gradients) override;
  void evaluate(const Scene& scene, const DensityGrid& density, std::span<RadianceSample> samples,
                bool gradients);
  /// `shadows`: the objects' shadow maps (null without objects).
  void evaluate(const Scene& scene, const Volume& density, std::span<RadianceSample> samples,
                bool gradients, StageTimer* timer, const ShadowMaps* shadows = nullptr);

 private:
  float delta1_, delta2_;
  bool factor_, log_, lamp_;
  ShadowMapSettings shadowMap_;
};

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
  explicit GradientSplatGpu(bool logSpace = false, bool occlusion = false,
                            std::optional<TaylorBounds> bounds = std::nullopt,
                            GpuPipeline pipeline = GpuPipeline::Compute, bool lamp = false)
      : log_(logSpace),
        occlusion_(occlusion),
        lamp_(lamp),
        bounds_(bounds),
        settingsBounds_(bounds),
        pipeline_(pipeline) {}
  bool needsGradients() const override { return true; }
  ReconstructionStats reconstruct(Frame& frame, const Scene& scene,
                                  std::span<const RadianceSample> samples, IVec3 dims,
                                  Progress* progress) override;
  ReconstructionStats reconstruct(const Scene& scene, const DensityGrid& density,
                                  std::span<const RadianceSample> samples, RadianceGrid& out);
  /// Splats into a new volume over `bounds` with `dims`.
  Volume reconstruct(const Volume& density, std::span<const RadianceSample> samples,
                     const Box& bounds, IVec3 dims, ReconstructionStats* stats, StageTimer* timer);

 private:
  bool log_, occlusion_, lamp_;
  std::optional<TaylorBounds> bounds_;          ///< this frame's (tightened with lamp_)
  std::optional<TaylorBounds> settingsBounds_;  ///< taylorBounds() of the settings
  GpuPipeline pipeline_;
  float sigmaT_ = 0.0f;  ///< for the occlusion weights
};

/// The per-voxel baseline on the GPU (twin of buildPerVoxelRadiance): S traced at every voxel
/// centre in one compute dispatch, empty neighbourhoods skipped. As a Reconstruction it
/// ignores the samples.
class PerVoxelGpu : public Reconstruction {
 public:
  explicit PerVoxelGpu(float delta1, ShadowMapSettings shadowMap = {})
      : delta1_(delta1), shadowMap_(shadowMap) {}
  bool needsGradients() const override { return false; }
  bool usesSamples() const override { return false; }
  ReconstructionStats reconstruct(Frame& frame, const Scene& scene,
                                  std::span<const RadianceSample> samples, IVec3 dims,
                                  Progress* progress) override;
  ReconstructionStats reconstruct(const Scene& scene, const DensityGrid& density,
                                  std::span<const RadianceSample> samples, RadianceGrid& out);
  /// `stats` receives traced and skipped; `shadows`: the objects' shadow maps (or null).
  Volume build(const Scene& scene, const Volume& density, const Box& bounds, IVec3 dims,
               ReconstructionStats* stats, StageTimer* timer, const ShadowMaps* shadows = nullptr);

 private:
  float delta1_;
  ShadowMapSettings shadowMap_;
};

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
  Image integrate(const Scene& scene, const DensityGrid& density, const RadianceGrid& radiance);
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
