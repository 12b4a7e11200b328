#include "render/sampled_methods.h"

#include "core/error.h"
#include "core/stages.h"
#include "render/methods.h"
#include "render/ray_marcher.h"
#include "sampling/dynamic_sampling.h"

namespace scatterlab {

std::unique_ptr<Sampler> makeSampler(Params& p, const Scene& scene, std::string& type) {
  const bool hasGaussians = scene.medium.density && scene.medium.density->gaussians();
  Json defaultSampler = hasGaussians ? Json{{"type", "gaussian-centres"}}
                                     : Json{{"type", "jittered"}, {"count", 512}};
  std::unique_ptr<Sampler> sampler;
  {
    const bool given = p.has("sampler");
    Params sp = given ? p.child("sampler") : Params(defaultSampler, p.keyPath("sampler"));
    if (!given) p.allow("sampler");
    type = sp.string("type", std::string(hasGaussians ? "gaussian-centres" : "jittered"));
    sampler = samplers().get(type, sp.keyPath("type"))(sp, scene);
    sp.finish();
  }
  return sampler;
}

namespace {

/// density -> sampler -> evaluate() -> reconstruction -> the CPU marcher. `gradient`, `rbf` and
/// `nearest` evaluate the sampler's samples; `adaptive` overrides evaluate() with dynamic
/// sampling.
class SampledMethod : public Method {
 public:
  SampledMethod(std::string name, std::string samplerType, MarchParams mp, IVec3 res,
                std::unique_ptr<Sampler> sampler, std::unique_ptr<RadianceEvaluator> evaluator,
                std::unique_ptr<Reconstruction> reconstruction)
      : name_(std::move(name)),
        samplerType_(std::move(samplerType)),
        mp_(mp),
        res_(res),
        sampler_(std::move(sampler)),
        evaluator_(std::move(evaluator)),
        reconstruction_(std::move(reconstruction)) {}

  RenderResult render(const Scene& scene, Progress* progress) override {
    RenderResult r;
    RenderStats& st = r.stats;
    fillCpuStats(st, name_, scene);
    r.density = std::make_shared<const DensityGrid>(buildDensityVolume(scene, st));
    const DensityGrid& density = *r.density;
    std::vector<RadianceSample> samples;
    {
      ScopedTimer t(st, "sampling");
      samples = sampler_->generate(scene, density);
    }
    samples = evaluate(scene, density, std::move(samples), st);
    auto radiance = std::make_shared<RadianceGrid>(scene.medium.bounds, res_);
    ReconstructionStats rs;
    {
      ScopedTimer t(st, "reconstruction");
      rs = reconstruction_->reconstruct(scene, density, samples, *radiance);
    }
    r.image = marchRadianceVolume(scene, density, *radiance, mp_.march, st, progress);
    r.radiance = std::move(radiance);
    st.samples = (long long)samples.size();
    st.extra["sampler"] = samplerType_;
    st.extra["uncovered_voxels"] = rs.uncovered;
    st.extra["radiance_resolution"] = {res_.x, res_.y, res_.z};
    st.extra["march_step"] = mp_.march.step;
    st.extra["delta1"] = mp_.delta1;
    r.samples = std::move(samples);
    return r;
  }

 protected:
  /// Computes S (and ∇S for `gradient`) of the sampler's samples, timed as "evaluation".
  virtual std::vector<RadianceSample> evaluate(const Scene& scene, const DensityGrid& density,
                                               std::vector<RadianceSample> samples,
                                               RenderStats& st) {
    ScopedTimer t(st, "evaluation");
    evaluator_->evaluate(scene, density, samples, /*gradients=*/name_ == "gradient");
    return samples;
  }

  std::string name_, samplerType_;
  MarchParams mp_;
  IVec3 res_;
  std::unique_ptr<Sampler> sampler_;
  std::unique_ptr<RadianceEvaluator> evaluator_;
  std::unique_ptr<Reconstruction> reconstruction_;
};

/// `adaptive` (paper Sec. 5): the initial samples are split by dynamic sampling, which
/// evaluates S and ∇S level by level, before the gradient reconstruction (Eq. 4).
class AdaptiveMethod : public SampledMethod {
 public:
  AdaptiveMethod(std::string samplerType, MarchParams mp, IVec3 res, DynamicSamplingSettings ds,
                 std::unique_ptr<Sampler> sampler, std::unique_ptr<RadianceEvaluator> evaluator,
                 std::unique_ptr<Reconstruction> reconstruction)
      : SampledMethod("adaptive", std::move(samplerType), mp, res, std::move(sampler),
                      std::move(evaluator), std::move(reconstruction)),
        ds_(std::move(ds)) {}

 protected:
  std::vector<RadianceSample> evaluate(const Scene& scene, const DensityGrid& density,
                                       std::vector<RadianceSample> initial,
                                       RenderStats& st) override {
    DynamicSamplingResult ds;
    {
      ScopedTimer t(st, "dynamic_sampling");
      ds = dynamicSampling(scene, density, std::move(initial), *evaluator_, ds_);
    }
    addDynamicSamplingStats(st, ds.levels, ds.samples, ds_);
    return std::move(ds.samples);
  }

 private:
  DynamicSamplingSettings ds_;
};

MethodFactory sampledFactory(const std::string& name) {
  return [name](Params& p, const Scene& scene, const std::string& backend) {
    if (backend == "gpu")
      throw ConfigError("method '" + name + "' has no GPU variant yet; use --backend cpu");
    const MarchParams mp = parseMarchParams(p, scene);
    const IVec3 res = parseRadianceResolution(p, scene);
    std::string type;
    std::unique_ptr<Sampler> sampler = makeSampler(p, scene, type);
    auto evaluator = radianceEvaluators().get("volume-tracer", p.keyPath("evaluator"))(p, scene);
    auto reconstruction = reconstructions().get(name, p.keyPath("method"))(p, scene);
    return std::unique_ptr<Method>(new SampledMethod(
        name, type, mp, res, std::move(sampler), std::move(evaluator), std::move(reconstruction)));
  };
}

}  // namespace

void registerSampledMethods() {
  for (const char* name : {"gradient", "rbf", "nearest"}) methods().add(name, sampledFactory(name));
  methods().add("adaptive", [](Params& p, const Scene& scene, const std::string& backend) {
    if (backend == "gpu")
      throw ConfigError("method 'adaptive' has no GPU variant yet; use --backend cpu");
    const MarchParams mp = parseMarchParams(p, scene);
    const IVec3 res = parseRadianceResolution(p, scene);
    DynamicSamplingSettings ds = parseDynamicSampling(p, scene);
    std::string type;
    std::unique_ptr<Sampler> sampler = makeSampler(p, scene, type);
    auto evaluator = radianceEvaluators().get("volume-tracer", p.keyPath("evaluator"))(p, scene);
    auto reconstruction = reconstructions().get("gradient", p.keyPath("method"))(p, scene);
    return std::unique_ptr<Method>(new AdaptiveMethod(type, mp, res, std::move(ds),
                                                      std::move(sampler), std::move(evaluator),
                                                      std::move(reconstruction)));
  });
}

}  // namespace scatterlab
