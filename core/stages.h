#pragma once
/// Stage interfaces of the volume pipelines (DESIGN.md §3): density -> sampler -> radiance
/// evaluator -> reconstruction -> integrator. Each is a small abstract class with one virtual
/// call per pass. The volumes a frame's stages share live in a Frame of the backend that runs
/// them (host grids on the CPU, 3D textures in gpu/), so a GPU pipeline never goes through the
/// host. A stage is registered once by name, with a variant per backend: CPU variants by
/// cpu/ and sampling/, GPU ones beside them by gpu/. Every variant is built from the same
/// PipelineSettings, parsed once by the method layer (methods/settings.h), so a key valid on
/// one backend is valid on the other.

#include <algorithm>
#include <any>
#include <array>
#include <cmath>
#include <functional>
#include <limits>
#include <memory>
#include <optional>
#include <span>
#include <stdexcept>
#include <string>
#include <typeinfo>
#include <vector>

#include "core/grid.h"
#include "core/image.h"
#include "core/max_density_grid.h"
#include "core/params.h"
#include "core/progress.h"
#include "core/registry.h"
#include "core/scene.h"
#include "core/stats.h"
#include "core/work_limits.h"

namespace scatterlab {

/// Where a stage runs. Every backend has the same keys; not every stage has every backend.
enum class Backend { Cpu = 0, Gpu = 1 };
inline constexpr int kBackendCount = 2;
/// "cpu" or "gpu".
const char* backendName(Backend b);

/// A radiance sample (paper Sec. 4): point, valid radius, source radiance S and its gradient.
struct RadianceSample {
  Vec3 position{0.0f};  ///< x_j, world space
  float radius = 0.0f;  ///< valid radius R_j, world units
  Vec3 S{0.0f};         ///< S(x_j, ω) per RGB channel (DESIGN.md §2; excludes σs and D)
  /// ∇S: dS[a] is the RGB derivative along world axis a (x, y, z), by central differences.
  Vec3 dS[3] = {Vec3(0.0f), Vec3(0.0f), Vec3(0.0f)};
  int level = 0;  ///< dynamic-sampling level (0 = initial set)
  /// Kernel weight for RBF reconstruction: w_j of the Gaussian a gaussian-centres sample came
  /// from (Zhou et al. 2007 weight their RBFs by it), 1 for other samplers.
  float weight = 1.0f;

  /// First-order Taylor estimate of S at p (paper Eq. 4's bracket).
  Vec3 taylor(const Vec3& p) const {
    const Vec3 d = p - position;
    return S + d.x * dS[0] + d.y * dS[1] + d.z * dS[2];
  }
};

/// View-ray marching settings, shared by every integrator that marches the view rays (render
/// keys march_step, min_transmittance, fast_march, march_scale; the ray-marcher's own keys are
/// RayMarcherSettings in shading/view_march.h).
struct MarchSettings {
  float step = 0.0f;  ///< view-ray step in world units
  /// March stops when transmittance falls below this (its share of the result is below it).
  float minTransmittance = 1e-6f;
  /// render.fast_march: empty-space skipping (MaxDensityGrid), tiles and, for volume lookups,
  /// one fused density + radiance lookup per step; false runs the plain march (the reference).
  bool fast = true;
  /// render.march_scale: march one ray per scale × scale pixels and upsample depth-aware
  /// (cpu/ray_marcher.h); 1 marches every pixel.
  int scale = 1;
  /// render.glow: next to a point or spot light a light's term of A (the factored march) or of
  /// S (exact) is its mean over the step's substeps (glowSubsteps); false: at the midpoint.
  bool glow = true;
  /// render.far_field: R of A's far field in voxels (FarField, shading/transport.h): the
  /// factored march looks the point lights beyond 2R up on a grid; 0 evaluates every light.
  float farField = 0.0f;
};

/// How the GPU backend runs the stages of a method with a radiance volume (render key
/// gpu_pipeline; docs/gpu.md). Both are kept and measured side by side.
enum class GpuPipeline {
  /// Compute shaders: the view march one invocation per pixel (gpu/view_march.h), the
  /// radiance splat as a binned gather (gpu/radiance_gather.h). Fast on every GPU, and on
  /// datacenter GPUs (H100/H200), which shade fragments on 4 of 132 SMs, by far.
  Compute,
  /// The paper's rasterised passes: slice marching with blending (gpu::SliceMarcher) and the
  /// radiance splat drawn slice by slice (gpu::GradientSplatGpu).
  Raster,
};

/// Shadow maps of the GPU backend (render.shadow_map, docs/objects.md): the visibility V_l of
/// scene objects towards each light, where the CPU traces shadow rays. Accepted and unused on
/// the CPU and without objects.
struct ShadowMapSettings {
  enum class Type { Vsm, Depth };
  Type type = Type::Vsm;  ///< variance shadow maps (the paper's) or a plain depth compare
  int resolution = 1024;  ///< texels per side of each map (a cube face for point lights)
  /// Depth bias in texels: the world size of one texel at the point, times this, is taken off
  /// the point's distance to the light (and surface points move this far along their normal).
  float bias = 1.0f;
  /// Filter width in texels (odd): VSM blurs the moments with a box filter this wide; depth
  /// compare averages this many × this many compares (PCF); 1 = none.
  int filter = 3;
  /// VSM light-bleeding reduction: Chebyshev's bound p is remapped (p − b)/(1 − b), clamped.
  float bleedReduction = 0.2f;
  bool given = false;  ///< the scene set `shadow_map`
};

/// A stage family's own settings struct, which core does not know (it is declared in the
/// family's own file, e.g. FroxelSettings in shading/screen_march.h): set by the family's key
/// parser (StageDecl), read by its variants with get<T>().
class StageOwnSettings {
 public:
  template <class T>
  void set(T v) {
    v_ = std::move(v);
  }
  /// Throws std::logic_error when no T was set (a variant built without its family's keys).
  template <class T>
  const T& get() const {
    if (const T* p = std::any_cast<T>(&v_)) return *p;
    throw std::logic_error(std::string("stage settings: no ") + typeid(T).name() + " was parsed");
  }
  bool has() const { return v_.has_value(); }

 private:
  std::any v_;
};

/// The volume tracer's steps and what it evaluates: the radiance evaluator's settings on both
/// backends (PipelineSettings::tracerSteps()), also dynamic sampling's GPU passes'.
struct TracerSteps {
  float delta1 = 0.0f;  ///< tracing step towards the lights (world units, the paper's Δ1)
  float delta2 = 0.0f;  ///< central-difference step of ∇S (world units, the paper's Δ2)
  /// Evaluate V = S / A (shading/transport.h, FactoredSourceRadiance) instead of S, and ∇V.
  bool factorLights = false;
  /// With factorLights: ln V and ∇ ln V (V clamped below at kMinV).
  bool logSpace = false;
  /// With factorLights: A and V include the near-lamp transmittance model (LampModel in
  /// shading/transport.h, docs/fidelity.md §8).
  bool lampModel = false;
  /// With factorLights: a sample whose sphere of validity, grown by `reach` (the radiance
  /// voxel's half-diagonal), meets no spot cone is not traced (LitReach, shading/transport.h):
  /// its V is never multiplied by a non-zero A. It holds V = 0 (ln V = ln kMinV). Points of
  /// radius 0 (dynamic sampling's probes) are always traced. 0: every sample is traced.
  float reach = 0.0f;
  /// CPU: the shadow rays traced 4 or 8 steps at once (cpu/shadow_rays.h, SIMD over a ray's
  /// steps) and stopped where no light gets through (kShadowDepthCutoff), as `exact`'s; false:
  /// shading/transport.h's scalar opticalDepth (the reference). render.fast_march.
  bool simdShadows = false;
  /// Whether the values are ln V: the one place where factorLights and logSpace combine.
  bool logValues() const { return factorLights && logSpace; }
};

/// The settings every stage variant is built from, whichever backend runs it. Parsed once,
/// with its key table, by parsePipelineSettings (methods/settings.h).
struct PipelineSettings {
  /// render.paper: the paper's algorithm exactly (every extension off, today's images).
  bool paper = false;
  /// Singular-light factorization (docs/fidelity.md): samples and the radiance volume hold
  /// V = S / A, A the analytic unshadowed source radiance of the lights, and the integrator
  /// multiplies A back at each step. Default: on for gradient and adaptive unless `paper`.
  bool factorLights = false;
  /// With factorLights: samples hold u = ln V and ∇u, the reconstruction interpolates u and
  /// stores V = exp(u). ln V is minus a light-weighted optical depth, nearly linear where V =
  /// exp(−τ) is convex, so first-order estimates do not undershoot (docs/fidelity.md).
  bool logSpace = false;
  /// With factorLights: A holds, per point or spot light inside the medium, the transmittance
  /// of a homogeneous medium of the light's own extinction, saturating at optical depth
  /// kLampDepth (LampModel, shading/transport.h), so V = S / A has no cusp at the lamp
  /// (docs/fidelity.md §8). Default: on with factorLights unless `paper`.
  bool lampModel = false;
  /// The method refines its samples where their error asks (a SampleRefiner runs: `adaptive`).
  /// Set from the method before any key is read; defaults may follow it (log_space).
  bool refinedSamples = false;
  /// The whole-scene fallback (key `voxel_switch`, methods whose row has one: gradient,
  /// adaptive; 0 = off, the paper's): where the medium's lit occupied voxels are at most
  /// voxelSwitch × the traces of the sampled path (PipelineMethod), the scene is rendered as
  /// per-voxel renders it.
  double voxelSwitch = 0.0;
  /// Occlusion-aware Eq. 4 weights: W_j(x)·exp(−σt·τ(x_j, x)), τ the optical depth between the
  /// sample and the voxel, so no sample contributes across a dense occluder.
  bool occlusionWeights = false;
  /// Bounded Taylor terms: each sample's first-order estimate is clamped, before it is
  /// weighted, to the range its quantity is known to lie in (V in [0, 1], ln V <= 0, S >= 0),
  /// so a steep gradient (self-shadowing dense smoke) cannot extrapolate far out of range and
  /// drag its neighbours' average (docs/fidelity.md). Default: on unless `paper`.
  bool boundedTaylor = false;
  MarchSettings march;
  /// render.gpu_pipeline: read by the GPU variants of two families (the reconstructions'
  /// splats and the ray-marcher), so it is the pipeline's key, not one family's; unused on the
  /// CPU (its row's `only`).
  GpuPipeline gpuPipeline = GpuPipeline::Compute;
  float delta1 = 0.0f;  ///< volume-tracing step towards the lights (the paper's Δ1)
  float delta2 = 0.0f;  ///< central-difference step of ∇S (the paper's Δ2)
  IVec3 radianceResolution{0};
  /// The half-diagonal of the 2×2×2-voxel cube around a radiance voxel centre (the support
  /// of its trilinear weight): TracerSteps::reach with factorLights.
  float radianceReach = 0.0f;
  ShadowMapSettings shadowMap;
  /// The settings of the integrator's and the refiner's own keys (light-space-march's,
  /// froxel's, dynamic sampling's, ...), parsed by their StageDecl; empty for stages without.
  StageOwnSettings integratorKeys, refinerKeys;

  TracerSteps tracerSteps() const {
    return {delta1,
            delta2,
            factorLights,
            logSpace,
            factorLights && lampModel,
            factorLights ? radianceReach : 0.0f,
            march.fast};
  }
  /// The samples and the radiance volume hold ln V (TracerSteps::logValues()).
  bool logValues() const { return tracerSteps().logValues(); }
};

/// With factorLights and logSpace the samples hold ln V, V clamped below at kMinV.
inline constexpr float kMinV = 1e-9f;

/// Paper Eq. 4's singularity: W_j(x) = R_j / max(‖x − x_j‖, kSingularEps·R_j), so W_j <= 1e9
/// (cpu/interpolation.h; the GPU gathers and splats read it as SL_SINGULAR_EPS).
inline constexpr float kSingularEps = 1e-9f;

/// The equal midpoint steps over a segment of `length` with steps of at most `step`: ⌈length /
/// step − kStepSlack⌉, at least 1 (a step may be kStepSlack × `step` longer). The view march,
/// the shadow rays, the occlusion weights and radial-blur count their steps with it, the GPU's
/// stepCount (gpu/shaders/common.glsl) likewise. Without the slack a ratio that is an integer in
/// exact arithmetic — a camera looking along an axis of a box whose depth is a whole number of
/// steps (its central rays), a shadow ray from a voxel centre straight along an axis — rounds to n
/// on one backend and n + 1 on the other (the CPU and a GPU round the box's entry and exit apart):
/// a camera zoomed to 0.5° at the glow scene's centre put 2.6 % between two pixels of the CPU's
/// and llvmpipe's images, 5.9e-4 relative L2 (docs/gpu.md, "CPU ≡ GPU on scenes nobody picked").
inline constexpr float kStepSlack = 1e-3f;
inline int stepCount(float length, float step) {
  return std::max(1, int(std::ceil(length / step - kStepSlack)));
}

/// LampModel's saturation depth κ (shading/transport.h): each lamp's model transmittance
/// falls from 1 at the lamp towards e^(−κ), so V = S / A lies in [0, e^κ] with it. Chosen by
/// measurement among 0.25, 0.5, 1, 2, 4, 8 (docs/fidelity.md §8).
inline constexpr float kLampDepth = 2.0f;
/// LampModel's m_l at q = k_l·distance, exp(−κ·q / (q + κ)): for a float (LampModel, the fused
/// lights' glow) or an xsimd batch (the SIMD march, the far field's build) alike.
template <class T>
T lampTransmittance(const T& q) {
  using std::exp;
  return exp(T(-kLampDepth) * q / (q + T(kLampDepth)));
}

/// The factored march's quadrature of A near a lamp (docs/fidelity.md, "Glows"): at a step of
/// length dt whose segment passes at distance r from a point or spot light (glowDistance), that
/// light's term of A is the mean over n = min(kGlowMaxSubsteps, ⌈kGlowRatio · dt / (r · w)⌉)
/// points spread evenly over the step (w: 1 for a point light, a spot's transition angle in
/// radians, at least kGlowMinAngle), not its value at the midpoint alone: 1/r², the phase function
/// and the cone's edge vary faster than a voxel there. n = 1 elsewhere. Both constants re-checked
/// on the 135 population scenes with a lamp (reach 2, 4, 8; 16, 32, 64 substeps) and kept
/// (docs/fidelity.md, "The glow's constants chosen on the population").
inline constexpr float kGlowRatio = 4.0f;
inline constexpr int kGlowMaxSubsteps = 32;
inline constexpr float kGlowMinAngle = 0.02f;
/// The substeps of a light's glow at a step `dist` from it (glowDistance): ⌈reach / dist⌉,
/// reach = kGlowRatio · dt / w, at most kGlowMaxSubsteps; 1 where dist >= reach. The GPU's
/// glowSubsteps (gpu/shaders/common.glsl) is the same.
inline int glowSubsteps(float dist, float reach) {
  if (!(dist < reach)) return 1;
  if (!(dist > 0.0f)) return kGlowMaxSubsteps;
  return int(std::min(std::ceil(reach / dist), float(kGlowMaxSubsteps)));
}
/// The distance from a light at p to the view-march step of length dt centred at x along the
/// unit dir: what glowSubsteps is given (the ray may pass the light inside the step). The GPU's
/// glowDistance (gpu/shaders/common.glsl) is the same.
inline float glowDistance(const Vec3& p, const Vec3& x, const Vec3& dir, float dt) {
  const Vec3 v = p - x;
  const float tc = std::clamp(glm::dot(v, dir), -0.5f * dt, 0.5f * dt);
  return glm::length(v - tc * dir);
}
/// w of a light for the glow's substeps: 1 for a point light, a spot's transition angle.
inline float glowAngle(const Light& l) {
  if (l.type != Light::Type::Spot) return 1.0f;
  const float w = std::acos(std::clamp(l.cosOuter, -1.0f, 1.0f)) -
                  std::acos(std::clamp(l.cosInner, -1.0f, 1.0f));
  return std::clamp(w, kGlowMinAngle, 1.0f);
}
/// A light's glow reach per unit of step (reach = this · dt): kGlowRatio / glowAngle for a point
/// or spot light, 0 for a directional one (no glow). Kept per light by LightFactor,
/// SourceRadiance and FusedLights (FusedLights::glow), and in GpuLight::glow (lamp.z), so that
/// no march step takes a spot's angles again.
inline float glowScale(const Light& l) {
  return l.type == Light::Type::Directional ? 0.0f : kGlowRatio / glowAngle(l);
}
/// The substeps of a light at `p` whose glowScale is `scale` at the view-march step of length dt
/// centred at x along unit dir: 1 where scale is 0, else glowSubsteps at the step's distance
/// from it (what `exact`'s SourceRadiance and the factored march's LightFactor average over).
inline int lightGlowSubsteps(float scale, const Vec3& p, const Vec3& x, const Vec3& dir, float dt) {
  if (!(scale > 0.0f)) return 1;
  return glowSubsteps(glowDistance(p, x, dir, dt), scale * dt);
}
/// The ray parameter of substep m of n of the step of length dt centred at t: the midpoints of
/// n equal parts.
inline float glowSubstepT(float t, float dt, int m, int n) {
  return t + ((float(m) + 0.5f) / float(n) - 0.5f) * dt;
}

/// Optical depth σt·τ at which a shadow ray stops (shadowDepthCutoff(), shading/transport.h; on
/// the GPU the shadow rays that skip empty space, common.glsl opticalDepth): exp(−25) ≈ 1.4e-11
/// of the light gets through, below what the float sums of a pixel resolve.
inline constexpr float kShadowDepthCutoff = 25.0f;

/// Dynamic sampling's error groups (sampling/dynamic_sampling.h errorBin(): a sample budget
/// splits worst group first): the bits of E's float below these are dropped (the exponent and 6
/// mantissa bits stay: 1/64 of an octave per group), and a group is counted from the threshold's,
/// at most kErrorBins − 1. The GPU's histograms have kErrorBins entries.
inline constexpr int kErrorBinShift = 17;
inline constexpr int kErrorBins = 4096;

/// LitReach (shading/transport.h): a spot cone is widened by kLitMargin radians and a ball by
/// the factor kLitGrow before they are tested, so CPU and GPU rounding never drops what A lights.
inline constexpr float kLitMargin = 1e-3f;
inline constexpr float kLitGrow = 1.001f;

/// Cells per edge of the bricks of A's far field (render.far_field): the CPU computes the grid
/// only next to bricks with density (cpu/far_field.h), the GPU keeps a mask of the lights near
/// each brick (far_mask.comp.glsl).
inline constexpr int kFarBrick = 8;

/// The physics constants the shaders share with the CPU, by the #define the GPU programs see
/// them under (gpu/shaders.h injects each one, so that no shader copies a number by hand).
struct SharedConstant {
  const char* define;
  float value;
};
inline constexpr SharedConstant kSharedConstants[] = {
    {"SL_MIN_V", kMinV},
    {"SL_SINGULAR_EPS", kSingularEps},
    {"SL_LAMP_DEPTH", kLampDepth},
    {"SL_SHADOW_DEPTH_CUTOFF", kShadowDepthCutoff},
    {"SL_BLOCK", float(MaxDensityGrid::kBlock)},  // voxels per edge of an empty-space block
    {"SL_ERROR_BIN_SHIFT", float(kErrorBinShift)},
    {"SL_ERROR_BINS", float(kErrorBins)},
    {"SL_LIT_MARGIN", kLitMargin},
    {"SL_LIT_GROW", kLitGrow},
    {"SL_GLOW_MAX_SUBSTEPS", float(kGlowMaxSubsteps)},
    {"SL_STEP_SLACK", kStepSlack},
    {"SL_FAR_BRICK", float(kFarBrick)},
};

/// The range a sample's Taylor estimate is clamped to, per channel, before it is weighted
/// (PipelineSettings::boundedTaylor): [0, 1] for V, [ln kMinV, 0] for ln V, [0, FLT_MAX] for S.
struct TaylorBounds {
  float lo = 0.0f, hi = 1.0f;
  Vec3 clamp(const Vec3& v) const { return glm::clamp(v, Vec3(lo), Vec3(hi)); }
};

/// The bounds for what `s`'s samples hold (nullopt when boundedTaylor is off).
inline std::optional<TaylorBounds> taylorBounds(const PipelineSettings& s) {
  if (!s.boundedTaylor) return std::nullopt;
  const bool lamp = s.tracerSteps().lampModel;
  if (s.logValues()) return TaylorBounds{std::log(kMinV), lamp ? kLampDepth : 0.0f};
  if (s.factorLights) return TaylorBounds{0.0f, lamp ? std::exp(kLampDepth) : 1.0f};
  return TaylorBounds{0.0f, std::numeric_limits<float>::max()};
}

/// The volumes of one frame, kept where the backend that renders the frame keeps them. The
/// method layer creates one per render (backendFrames()) and hands it to every stage; a stage
/// variant casts it to its own backend's frame type (stages and frame share a backend by
/// construction).
class Frame {
 public:
  virtual ~Frame() = default;
  virtual Backend backend() const = 0;
  /// Builds the scene's density volume over medium.bounds at medium.resolution.
  virtual void buildDensity(const Scene& scene) = 0;
  /// The density volume in host memory (the samplers run on the CPU); read back once where
  /// the volume lives on a device.
  virtual const DensityGrid& hostDensity() = 0;
  /// Waits until the work queued so far is done, so that a stage's wall time is its own.
  virtual void sync() {}
  /// Forgets per-render state (device timers) before a frame whose density is kept is rendered
  /// again (Method::retainDensity).
  virtual void newRender() {}
  /// Writes the backend's facts into `stats`: device, and e.g. per-pass device times.
  virtual void report(RenderStats& stats) = 0;
  /// The density and source-radiance volumes in host memory, for export; null where they
  /// live on a device (or were not built).
  virtual std::shared_ptr<const DensityGrid> exportDensity() const { return nullptr; }
  virtual std::shared_ptr<const RadianceGrid> exportRadiance() const { return nullptr; }
  /// Method::imageOnDevice: the integrator may leave the image in a device texture of this
  /// frame (a backend without one ignores the request).
  virtual void keepImageOnDevice(bool) {}
  /// The image an integrator left on the device in this render, if any: (GL texture name,
  /// width, height).
  virtual std::optional<std::array<unsigned, 3>> deviceImage() const { return std::nullopt; }
  /// How many cells of each regular grid of `grids` (their dims) over the density's box hold a
  /// voxel centre with D > 0 (scatterlab::occupiedCells): the cell samplers' occupancy. From
  /// hostDensity() here, grid by grid; a GPU frame counts every grid of the call in one pass on
  /// the device from its own density volume and reads back 4 bytes per grid, not the volume
  /// (issue 33).
  virtual std::vector<long long> countOccupiedCells(std::span<const IVec3> grids);
  /// The occupied cells of a `dims` grid (as countOccupiedCells), ascending. A GPU frame reads
  /// them from its last count when that counted `dims` (no new pass).
  virtual std::vector<int> occupiedCellList(IVec3 dims);
  /// Per cell of a `dims` grid (as countOccupiedCells, indexed as occupiedCells()), how many
  /// voxel centres with D > 0 it holds. A GPU frame counts them in one pass and reads them back
  /// (one wait, 4 bytes per cell).
  virtual std::vector<int> occupiedVoxelsPerCell(IVec3 dims);
  /// Whether countOccupiedCells counts several grids for about the price of one (a GPU frame:
  /// one pass and one wait for all), so that a search may ask for grids it may not need.
  virtual bool countsGridsTogether() const { return false; }
};

/// The voxel-centre → cell map of one axis of occupiedCells(): voxel centre u of `voxels` lies
/// in cell min(cells − 1, int((u + 0.5) / voxels · cells)) (float arithmetic as written; the GPU
/// pass looks the maps up instead of recomputing them).
std::vector<int> voxelCells(int voxels, int cells);
/// The first voxel of each of those cells and one past the last (`cells` + 1 entries; a cell
/// that holds no voxel centre starts where the next one does): cell c holds voxels
/// [first[c], first[c + 1]).
std::vector<int> cellStarts(int voxels, int cells);

/// The cells of a regular `dims` grid over `g`'s box that hold a voxel centre with D > 0 (linear
/// indices i + nx·(j + ny·k), ascending).
std::vector<int> occupiedCells(const DensityGrid& g, IVec3 dims);
/// How many they are (occupiedCells(g, dims).size(), without the list).
long long countOccupiedCells(const DensityGrid& g, IVec3 dims);
/// Per cell of that grid (linear index as occupiedCells()), its voxel centres with D > 0.
std::vector<int> occupiedVoxelsPerCell(const DensityGrid& g, IVec3 dims);

/// The CPU backend's frame: the volumes as host grids. No GL context.
class HostFrame : public Frame {
 public:
  HostFrame() = default;
  /// A frame over an existing density volume (tests and benchmarks).
  explicit HostFrame(DensityGrid density)
      : density(std::make_shared<DensityGrid>(std::move(density))) {}
  Backend backend() const override { return Backend::Cpu; }
  void buildDensity(const Scene& scene) override;
  const DensityGrid& hostDensity() override { return *density; }
  void report(RenderStats& stats) override;
  std::shared_ptr<const DensityGrid> exportDensity() const override { return density; }
  std::shared_ptr<const RadianceGrid> exportRadiance() const override { return radiance; }

  std::shared_ptr<DensityGrid> density;
  std::shared_ptr<RadianceGrid> radiance;  ///< set by the reconstruction
  /// The view march's steps looked up and jumped over (stats march_steps,
  /// march_steps_skipped), set by a marching integrator.
  std::optional<std::array<long long, 2>> marchSteps;
  /// Point-light terms evaluated for A's far field this frame (stats far_field_terms; 0 when the
  /// grid was kept), set by the factored march with render.far_field.
  std::optional<long long> farFieldTerms;
};

/// The scene's density volume on the host (medium.bounds, medium.resolution): what
/// HostFrame::buildDensity builds, for tests and benchmarks.
DensityGrid buildDensityVolume(const Scene& scene);

/// A backend: makes the frames its stage variants work in.
struct BackendEntry {
  /// A frame for a method built from `settings` (the GPU's reads gpuPipeline: how the density
  /// of Gaussians is built).
  std::function<std::unique_ptr<Frame>(const PipelineSettings& settings)> makeFrame;
  /// For backend "auto": whether this backend should be chosen now (e.g. a hardware GPU is
  /// present), with a sentence saying what was found. May create a GL context.
  std::function<bool(std::string* why)> preferred;
  /// What of `scene` this backend cannot render yet, as a sentence ending in the way out (e.g.
  /// "...; use --backend cpu"); empty when it can. Null: it renders everything.
  std::function<std::string(const Scene& scene)> unsupported;
};
/// Indexed by Backend; the CPU entry is always there, the GPU one when gpu/ registered it.
std::array<BackendEntry, kBackendCount>& backends();

/// Chooses sample points and valid radii (S and dS left zero).
class Sampler {
 public:
  virtual ~Sampler() = default;
  /// Generates samples for the scene; `density` is its density volume. Deterministic for a
  /// given scene and parameters, and reads nothing of the scene but its medium (not the
  /// lights, camera or objects): a method that keeps its density between renders
  /// (Method::retainDensity) keeps the samples with it.
  virtual std::vector<RadianceSample> generate(const Scene& scene, const DensityGrid& density) = 0;
  /// The same in a render's frame (what the pipeline calls): by default generate() on the
  /// frame's hostDensity() where the sampler reads the density; a sampler that only needs the
  /// density's occupancy asks the frame for it (Frame::occupiedCells), which a GPU frame counts
  /// without reading the volume back.
  virtual std::vector<RadianceSample> generate(Frame& frame, const Scene& scene);
  /// About how many samples generate() will make for `scene` (the medium the sampler was made
  /// for): what the render's plan counts (memory, tracing work) before anything is built.
  virtual long long plannedCount(const Scene& scene) const = 0;
  /// Whether generate() reads the density volume. When not, it gets an empty grid, and a GPU
  /// frame reads nothing back for it (a density read-back is a host round trip of the whole
  /// volume).
  virtual bool readsDensity() const { return true; }
};

/// Computes S (and ∇S when `gradients`) at each sample's position, by volume tracing with step
/// delta1 and central differences with step delta2 (paper Sec. 4). The view direction at x is
/// towards scene.camera.position. Samples are host data (uploaded and read back by device
/// variants); the density is the frame's.
class RadianceEvaluator {
 public:
  virtual ~RadianceEvaluator() = default;
  virtual void evaluate(Frame& frame, const Scene& scene, std::span<RadianceSample> samples,
                        bool gradients) = 0;
};

/// What a reconstruction did.
struct ReconstructionStats {
  long long uncovered = 0;  ///< voxels with density but no covering sample
  long long traced = 0;     ///< voxels whose S was traced (per-voxel)
  long long skipped = 0;    ///< voxels left at 0: no density in their neighbourhood (per-voxel)
};

/// Builds the frame's source-radiance volume (over medium.bounds with `dims` voxels) from the
/// samples, or by tracing (per-voxel, which takes no samples).
class Reconstruction {
 public:
  virtual ~Reconstruction() = default;
  /// Whether the samples need ∇S (the evaluator computes it only then).
  virtual bool needsGradients() const = 0;
  /// False for reconstructions that trace S themselves (no sampler runs before them).
  virtual bool usesSamples() const { return true; }
  virtual ReconstructionStats reconstruct(Frame& frame, const Scene& scene,
                                          std::span<const RadianceSample> samples, IVec3 dims,
                                          Progress* progress) = 0;
};

/// Marches camera rays through the frame's density (and radiance) volumes into an image.
class Integrator {
 public:
  virtual ~Integrator() = default;
  /// False for integrators that trace S themselves at every step (`exact`).
  virtual bool needsRadiance() const { return true; }
  virtual Image integrate(Frame& frame, const Scene& scene, Progress* progress) = 0;
  /// Adds the integrator's facts to the stats (slices, keys it did not use, ...).
  virtual void describe(RenderStats& stats) const {}
};

/// Builds one backend's variant of a stage. `Args` are what the variant is built from.
template <class Stage, class... Args>
using StageMaker = std::function<std::unique_ptr<Stage>(Args...)>;

/// A table of render keys and the code that reads them (into PipelineSettings, the same
/// whichever backend runs). Each key's name is written once, in its table's row and its read,
/// side by side in one file.
struct KeyGroup {
  const std::vector<KeyDoc>& (*table)() = nullptr;
  /// Reads the table's keys from the render object; must not call finish(). Reads of other
  /// groups the method has come first (a stage's parser may use what they set, e.g. `paper`).
  void (*parse)(Params& render, const Scene& scene, PipelineSettings& settings) = nullptr;
};

/// The light-march (volume-tracing) work a stage does itself, which the work bound counts
/// before a render (core/work_limits.h): a march to every light from ...
enum class LightWork {
  None,
  EveryViewStep,  ///< ... every view-ray step (exact)
  EveryVoxel,     ///< ... every voxel of the radiance volume (per-voxel)
};

/// The work and host memory a stage's own keys imply (StageDecl::work), which
/// checkRenderPlan bounds (core/work_limits.h). Keys are relative to the render object.
struct StageWork {
  /// View-ray terms the stage sums by its own steps (0: none), against kMaxViewSteps; the key
  /// named when there are too many, and how they arise ("320x240 pixels x 32 steps").
  double viewTerms = 0;
  std::string termsKey = {}, termsHow = {};
  /// Points that each march to every light by delta1 (0: none), and which ("at every one of
  /// 1e+06 froxels").
  double lightPoints = 0;
  std::string lightWhat = {};
  /// The host arrays of the stage's CPU variant.
  std::vector<MemoryPlan::Item> cpuArrays = {};
  /// Refiners: the stage traces, for each planned sample, S and its 6 central differences of
  /// ∇S, and `probesPerSample` more points (dynamic sampling's level-0 probes; the key
  /// `probesKey` sets them), each kept as a sample while it runs.
  bool tracesGradients = false;
  int probesPerSample = 0;
  std::string probesKey = {};
  /// Arrays the stage allocates whichever backend runs (dynamic sampling's finest grid buffer).
  std::vector<MemoryPlan::Item> arrays = {};
};

/// What a stage family declares, the same for each of its backends' variants (Mitsuba's plugin
/// properties): the render keys it reads and the facts the method layer plans with. Declared
/// once per family, in the family's own file (with its settings struct, in shading/, where both
/// backends' variants read one), and registered by the registration of its CPU variant.
struct StageDecl {
  /// Its own keys (none: empty). The method layer reads them, whatever backend runs, before
  /// any variant is built, and lists them among the method's keys (methodKeys()).
  std::vector<KeyGroup> keys = {};
  /// Integrators: the view rays step by march_step (the view march's keys are read:
  /// march_step, min_transmittance, fast_march, march_scale). False: the integrator has its
  /// own steps (light-space-march).
  bool viewMarch = false;
  /// Integrators: one ray per (low-resolution) pixel, so camera.spp must be 1 (a ConfigError
  /// when the keys are read).
  bool onePerPixel = false;
  /// Integrators: the CPU variant fuses the density and radiance volumes when fast_march is on
  /// and their grids agree (one more volume in the memory plan).
  bool fusedVolumeOnCpu = false;
  LightWork lightWork = LightWork::None;
  /// Integrators with their own steps or host arrays (the competitors): what they do and
  /// allocate by their own keys, which the render plan checks before a render. Null: nothing
  /// beyond the view march and lightWork.
  StageWork (*work)(const Scene& scene, const PipelineSettings& settings) = nullptr;
};

/// A registered stage: its declaration and one maker per backend, empty where that backend has
/// no variant.
template <class Maker>
struct StageVariants {
  StageDecl decl;
  std::array<Maker, kBackendCount> on;
  bool has(Backend b) const { return bool(on[int(b)]); }
};

/// Name -> declaration and per-backend variants. declare() creates the entry (once per name, in
/// the stage family's file); addVariant() adds a backend's variant to a declared name, so gpu/
/// adds its variants beside the CPU ones, and a variant of a name never declared (a misspelling
/// in a register function) is a std::logic_error at initialize(), not a stage without keys.
template <class Maker>
class StageRegistry : public Registry<StageVariants<Maker>> {
 public:
  using Registry<StageVariants<Maker>>::Registry;
  void declare(const std::string& name, StageDecl decl) {
    this->entry(name).decl = std::move(decl);
  }
  void addVariant(const std::string& name, Backend b, Maker make) {
    if (!this->contains(name))
      throw std::logic_error("a " + std::string(backendName(b)) + " variant of '" + name +
                             "', which no stage declares (declare() it first)");
    this->entry(name).on[int(b)] = std::move(make);
  }
};

/// Samplers run on the host for every backend and read their own keys (render.sampler.*).
template <class Stage>
using StageFactory = std::function<std::unique_ptr<Stage>(Params& params, const Scene& scene)>;
using EvaluatorMaker = StageMaker<RadianceEvaluator, const PipelineSettings&>;
using ReconstructionMaker = StageMaker<Reconstruction, const PipelineSettings&>;
using IntegratorMaker = StageMaker<Integrator, const PipelineSettings&>;

Registry<StageFactory<Sampler>>& samplers();
StageRegistry<EvaluatorMaker>& radianceEvaluators();
StageRegistry<ReconstructionMaker>& reconstructions();
StageRegistry<IntegratorMaker>& integrators();

}  // namespace scatterlab
