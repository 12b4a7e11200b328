#include "cpu/integrators.h"

#include <tbb/parallel_for.h>

#include <memory>

#include "core/stages.h"
#include "cpu/far_field.h"
#include "cpu/froxel.h"
#include "cpu/fused_march.h"
#include "cpu/fused_volume.h"
#include "cpu/jittered_march.h"
#include "cpu/light_space_march.h"
#include "cpu/radial_blur.h"
#include "cpu/ray_marcher.h"
#include "cpu/shadow_rays.h"
#include "shading/screen_march.h"
#include "shading/transport.h"
#include "shading/view_march.h"

namespace scatterlab {

namespace {

/// The march's lookups through a FusedVolume by the SIMD kernels (cpu/fused_march.h), in
/// runs of steps (MarchesSpans in cpu/ray_marcher.h). With a light factor (the volume holds
/// V = S / A) the span kernel multiplies S of the steps that contribute by A(x, ω), the point
/// and spot lights SIMD over each group of steps (`lights`) and the directional ones once per
/// ray: the same lookups, exp and sums as without one.
struct FusedLookup {
  const FusedVolume& volume;
  const LightFactor* factor;  ///< A for one step (operator()); null: unfactored
  const FusedLights* lights;  ///< the same A for the span kernels; null exactly when factor is
  FusedSpanKernel span;
  FusedMarchConstants c;
  /// One step (DensitySourceLookup's interface; the fast march calls marchSpan instead).
  bool operator()(const Vec3& u, const Ray& r, float t, float dt, float& D, Vec3& S) const {
    alignas(16) float v[4];
    volume.sample(u, v);
    D = v[0];
    if (D <= 0.0f) return false;
    S = Vec3(v[1], v[2], v[3]);
    // V = 0: no A to evaluate
    if (factor && S != Vec3(0.0f)) S *= factor->overStep(r, t, dt);
    return true;
  }
  void marchSpan(const Ray& r, const Vec3& u0, const Vec3& du, float t0, float dt, int i, int end,
                 Vec3& L, float& T, float& wt) const {
    const FusedRay fr{{u0.x, u0.y, u0.z}, {du.x, du.y, du.z}, t0, dt};
    FusedMarchState s{{L.x, L.y, L.z}, T, wt};
    if (lights) {
      const Vec3 toViewer = -r.dir, a = lights->directional(toViewer);
      FusedFactor f{lights,
                    {r.origin.x, r.origin.y, r.origin.z},
                    {r.dir.x, r.dir.y, r.dir.z},
                    {toViewer.x, toViewer.y, toViewer.z},
                    {a.x, a.y, a.z}};
      if (lights->farRadius > 0.0f) {  // only the lights within 2R of the span's steps
        thread_local std::vector<int> near;
        lights->nearSpan(f, t0 + (float(i) + 0.5f) * dt, t0 + (float(end) - 0.5f) * dt, near);
        f.near = near.data();
        f.nearCount = int(near.size());
      }
      span(volume.view(), c, fr, i, end, s, &f);
    } else {
      span(volume.view(), c, fr, i, end, s, nullptr);
    }
    L = Vec3(s.L[0], s.L[1], s.L[2]);
    T = s.T;
    wt = s.wt;
  }
};

/// The plain march's lookups where the volume holds V = S / A: S = V · A over the step
/// (LightFactor::overStep, the glow).
struct FactoredLookup {
  const DensityGrid& density;
  const RadianceGrid& radiance;
  const LightFactor& A;
  Vec3 scale, offset;  ///< the radiance volume's index space
  bool operator()(const Vec3& u, const Ray& r, float t, float dt, float& D, Vec3& S) const {
    D = density.sampleIndex(u);
    if (D <= 0.0f) return false;
    const Vec3 x = r.at(t);
    S = radiance.sampleIndex(x * scale + offset);
    if (S != Vec3(0.0f)) S *= A.overStep(r, t, dt);  // V = 0: no A to evaluate
    return true;
  }
};

/// `exact`'s lookups: S traced over the step (SourceRadiance::overStep, the glow).
struct ExactLookup {
  const DensityGrid& density;
  const SourceRadiance& source;
  bool operator()(const Vec3& u, const Ray& r, float t, float dt, float& D, Vec3& S) const {
    D = density.sampleIndex(u);
    if (D <= 0.0f) return false;
    S = source.overStep(r, t, dt);
    return true;
  }
};

class RayMarcher : public Integrator {
 public:
  explicit RayMarcher(const PipelineSettings& s)
      : march_(s.march),
        keys_(s.integratorKeys.get<RayMarcherSettings>()),
        factored_(s.factorLights),
        lampModel_(s.tracerSteps().lampModel),
        delta1_(s.delta1) {}
  Image integrate(Frame& frame, const Scene& scene, Progress* progress) override {
    HostFrame& f = static_cast<HostFrame&>(frame);
    MarchCounts counts;
    Image img = march(f, scene, progress, counts);
    f.marchSteps = {counts.looked.load(), counts.skipped.load()};
    return img;
  }

 private:
  Image march(HostFrame& f, const Scene& scene, Progress* progress, MarchCounts& counts) {
    const RadianceGrid& radiance = *f.radiance;
    if (progress) progress->restart("march", scene.camera.height);
    // The volume holds V = S / A; A is analytic (one evaluation per light and step).
    const LampModel lamp = lampModel_ ? LampModel(scene, *f.density) : LampModel();
    LightFactor A(scene, lamp, march_.glow);
    // A's far field (FarFieldCache): kept from render to render while what it depends on stays
    // (a camera move: the far field is isotropic), updated for the lamps that changed; the
    // plain march and the SIMD kernels both take it.
    const bool far = factored_ && march_.farField > 0.0f;
    if (far) {
      long long terms = 0;
      A.setFarField(&farField_.update(scene, lamp, f.density, march_.farField, &terms));
      f.farFieldTerms = terms;
    }
    if (march_.fast && FusedVolume::compatible(*f.density, radiance)) {
      // A frame over the density and radiance it was built from (a camera move: both kept, the
      // same objects; HostFrame makes new ones whenever it builds them) keeps it as it is.
      if (fusedDensity_.lock() != f.density || fusedRadiance_.lock() != f.radiance ||
          fused_.half() != keys_.halfFloat) {
        fused_.build(*f.density, radiance, keys_.halfFloat);
        fusedDensity_ = f.density;
        fusedRadiance_ = f.radiance;
      }
      FusedLights lights(scene, lamp, march_.glow);
      if (far) lights.setFarField(&farField_.grid());
      const FusedLookup lookup{fused_,
                               factored_ ? &A : nullptr,
                               factored_ ? &lights : nullptr,
                               fusedSpanKernel(keys_.simd),
                               {scene.medium.sigmaT, scene.medium.albedo, march_.minTransmittance}};
      return marchWith(scene, *f.density, lookup, march_, progress, delta1_, &counts);
    }
    const Vec3 s = radiance.indexScale(), o = radiance.indexOffset();
    if (factored_) {
      const FactoredLookup lookup{*f.density, radiance, A, s, o};
      return marchWith(scene, *f.density, lookup, march_, progress, delta1_, &counts);
    }
    const auto lookup = [&](const Vec3& x, const Vec3&) { return radiance.sampleIndex(x * s + o); };
    return marchImage(scene, *f.density, lookup, march_, progress, delta1_, &counts);
  }

  MarchSettings march_;
  RayMarcherSettings keys_;
  /// The fast march's volume, kept from render to render: its storage is written again, not
  /// allocated and faulted in anew (a Renderer's frames, the harness's repetitions).
  FusedVolume fused_;
  std::weak_ptr<const DensityGrid> fusedDensity_;    ///< what fused_ was built from
  std::weak_ptr<const RadianceGrid> fusedRadiance_;  ///< likewise
  /// A's far field (render.far_field), kept likewise and updated light by light.
  FarFieldCache farField_;
  bool factored_;
  bool lampModel_;  ///< A includes LampModel's m_l (PipelineSettings::lampModel)
  float delta1_;
};

class ExactIntegrator : public Integrator {
 public:
  explicit ExactIntegrator(const PipelineSettings& s) : march_(s.march), delta1_(s.delta1) {}
  bool needsRadiance() const override { return false; }
  Image integrate(Frame& frame, const Scene& scene, Progress* progress) override {
    const DensityGrid& density = frame.hostDensity();
    if (progress) progress->restart("exact", scene.camera.height);
    // The shadow rays stop at an optical depth where no light gets through. (Skipping empty
    // blocks along them too, SourceRadiance's `skip`, was measured slower on smoke1: their
    // steps of three voxels cross a block in about three lookups, and few blocks are empty.)
    // With the fast march the shadow rays are traced with SIMD over their steps
    // (cpu/shadow_rays.h); the plain march keeps the scalar opticalDepth.
    const SimdShadowRays shadows(density);
    SourceRadiance source(scene, density, delta1_, nullptr, march_.fast,
                          march_.fast ? shadows.fn() : ShadowDepthFn{});
    source.setGlow(march_.glow);
    MarchCounts counts;
    // S over each step (SourceRadiance::overStep): a lamp's glow averaged over substeps.
    const ExactLookup lookup{density, source};
    Image img = marchWith(scene, density, lookup, march_, progress, delta1_, &counts);
    if (auto* host = dynamic_cast<HostFrame*>(&frame))
      host->marchSteps = {counts.looked.load(), counts.skipped.load()};
    return img;
  }

 private:
  MarchSettings march_;
  float delta1_;
};

/// `jittered-march` (cpu/jittered_march.h): no radiance volume, S traced per sample.
class JitteredMarchIntegrator : public Integrator {
 public:
  explicit JitteredMarchIntegrator(const PipelineSettings& s)
      : s_(s.integratorKeys.get<JitteredMarchSettings>()), march_(s.march), delta1_(s.delta1) {}
  bool needsRadiance() const override { return false; }
  Image integrate(Frame& frame, const Scene& scene, Progress* progress) override {
    return jitteredMarch(scene, frame.hostDensity(), s_, march_, delta1_, progress);
  }
  void describe(RenderStats& stats) const override { describeJitteredMarch(stats, s_); }

 private:
  JitteredMarchSettings s_;
  MarchSettings march_;
  float delta1_;
};

/// `froxel` (cpu/froxel.h).
class FroxelIntegrator : public Integrator {
 public:
  explicit FroxelIntegrator(const PipelineSettings& s)
      : s_(s.integratorKeys.get<FroxelSettings>()),
        minT_(s.march.minTransmittance),
        delta1_(s.delta1) {}
  bool needsRadiance() const override { return false; }
  Image integrate(Frame& frame, const Scene& scene, Progress* progress) override {
    passes_ = Json::object();
    return froxelRender(scene, frame.hostDensity(), s_, delta1_, minT_, progress, &passes_);
  }
  void describe(RenderStats& stats) const override {
    describeFroxel(stats, s_);
    stats.extra["pass_ms"] = passes_;
  }

 private:
  FroxelSettings s_;
  float minT_, delta1_;
  Json passes_;
};

}  // namespace

void registerIntegrators() {
  integrators().declare("jittered-march", jitteredMarchStage());
  integrators().addVariant("jittered-march", Backend::Cpu, [](const PipelineSettings& s) {
    return std::unique_ptr<Integrator>(new JitteredMarchIntegrator(s));
  });
  integrators().declare("froxel", froxelStage());
  integrators().addVariant("froxel", Backend::Cpu, [](const PipelineSettings& s) {
    return std::unique_ptr<Integrator>(new FroxelIntegrator(s));
  });
  integrators().declare("ray-marcher", rayMarcherStage());
  integrators().addVariant("ray-marcher", Backend::Cpu, [](const PipelineSettings& s) {
    return std::unique_ptr<Integrator>(new RayMarcher(s));
  });
  integrators().declare("exact", {.viewMarch = true, .lightWork = LightWork::EveryViewStep});
  integrators().addVariant("exact", Backend::Cpu, [](const PipelineSettings& s) {
    return std::unique_ptr<Integrator>(new ExactIntegrator(s));
  });
  registerLightSpaceMarch();
  registerRadialBlur();
}

}  // namespace scatterlab
