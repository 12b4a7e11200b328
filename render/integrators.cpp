#include "render/integrators.h"

#include "core/stages.h"
#include "core/transport.h"
#include "render/light_space_march.h"
#include "render/radial_blur.h"
#include "render/froxel.h"
#include "render/jittered_march.h"
#include "render/ray_marcher.h"

namespace scatterlab {

namespace {

class RayMarcher : public Integrator {
 public:
  explicit RayMarcher(const PipelineSettings& s)
      : march_(s.march),
        slicingGiven_(s.slicingGiven),
        factored_(s.factorLights),
        delta1_(s.delta1) {}
  Image integrate(Frame& frame, const Scene& scene, Progress* progress) override {
    const HostFrame& f = static_cast<const HostFrame&>(frame);
    const RadianceGrid& radiance = *f.radiance;
    if (progress) progress->restart("march", scene.camera.height);
    const Vec3 s = radiance.indexScale(), o = radiance.indexOffset();
    if (factored_) {
      // The volume holds V = S / A; A is analytic (one evaluation per light and step).
      const LightFactor A(scene);
      const auto lookup = [&](const Vec3& x, const Vec3& toViewer) {
        return radiance.sampleIndex(x * s + o) * A(x, toViewer);
      };
      return marchImage(scene, *f.density, lookup, march_, progress, delta1_);
    }
    const auto lookup = [&](const Vec3& x, const Vec3&) { return radiance.sampleIndex(x * s + o); };
    return marchImage(scene, *f.density, lookup, march_, progress, delta1_);
  }
  void describe(RenderStats& stats) const override {
    // The CPU marcher steps along each ray: a slicing the scene asks for has no meaning here.
    if (slicingGiven_) stats.extra["unused_keys"] = {"render.slicing"};
  }

 private:
  MarchSettings march_;
  bool slicingGiven_;
  bool factored_;
  float delta1_;
};

class ExactIntegrator : public Integrator {
 public:
  explicit ExactIntegrator(const PipelineSettings& s) : march_(s.march), delta1_(s.delta1) {}
  bool needsRadiance() const override { return false; }
  Image integrate(Frame& frame, const Scene& scene, Progress* progress) override {
    const DensityGrid& density = frame.hostDensity();
    if (progress) progress->restart("exact", scene.camera.height);
    const SourceRadiance source(scene, density, delta1_);
    return marchImage(scene, density, source, march_, progress, delta1_);
  }

 private:
  MarchSettings march_;
  float delta1_;
};

/// `jittered-march` (render/jittered_march.h): no radiance volume, S traced per sample.
class JitteredMarchIntegrator : public Integrator {
 public:
  explicit JitteredMarchIntegrator(const PipelineSettings& s)
      : s_(s.jittered), march_(s.march), delta1_(s.delta1) {}
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

/// `froxel` (render/froxel.h).
class FroxelIntegrator : public Integrator {
 public:
  explicit FroxelIntegrator(const PipelineSettings& s)
      : s_(s.froxel), minT_(s.march.minTransmittance), delta1_(s.delta1) {}
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
  integrators().addVariant("jittered-march", Backend::Cpu, [](const PipelineSettings& s) {
    return std::unique_ptr<Integrator>(new JitteredMarchIntegrator(s));
  });
  integrators().addVariant("froxel", Backend::Cpu, [](const PipelineSettings& s) {
    return std::unique_ptr<Integrator>(new FroxelIntegrator(s));
  });
  integrators().addVariant("ray-marcher", Backend::Cpu, [](const PipelineSettings& s) {
    return std::unique_ptr<Integrator>(new RayMarcher(s));
  });
  integrators().addVariant("exact", Backend::Cpu, [](const PipelineSettings& s) {
    return std::unique_ptr<Integrator>(new ExactIntegrator(s));
  });
  registerLightSpaceMarch();
  registerRadialBlur();
}

}  // namespace scatterlab
