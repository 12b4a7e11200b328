#include "render/sampled_methods.h"

#include "core/error.h"
#include "core/stages.h"
#include "render/methods.h"
#include "render/ray_marcher.h"
#include "sampling/dynamic_sampling.h"

namespace scatterlab {

namespace {

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
    st.method = name_;
    st.backend = "cpu";
    st.device = "CPU (TBB)";
    st.width = scene.camera.width;
    st.height = scene.camera.height;
    const DensityGrid density = buildDensityVolume(scene, st);
    std::vector<RadianceSample> samples;
    {
      ScopedTimer t(st, "sampling");
      samples = sampler_->generate(scene, density);
    }
    {
      ScopedTimer t(st, "evaluation");
      evaluator_->evaluate(scene, density, samples, /*gradients=*/name_ == "gradient");
    }
    RadianceGrid radiance(scene.medium.bounds, res_);
    ReconstructionStats rs;
    {
      ScopedTimer t(st, "reconstruction");
      rs = reconstruction_->reconstruct(scene, density, samples, radiance);
    }
    r.image = marchRadianceVolume(scene, density, radiance, mp_.march, st, progress);
    st.samples = (long long)samples.size();
    r.samples = std::move(samples);
    st.extra["sampler"] = samplerType_;
    st.extra["uncovered_voxels"] = rs.uncovered;
    st.extra["radiance_resolution"] = {res_.x, res_.y, res_.z};
    st.extra["march_step"] = mp_.march.step;
    st.extra["delta1"] = mp_.delta1;
    return r;
  }

 private:
  std::string name_, samplerType_;
  MarchParams mp_;
  IVec3 res_;
  std::unique_ptr<Sampler> sampler_;
  std::unique_ptr<RadianceEvaluator> evaluator_;
  std::unique_ptr<Reconstruction> reconstruction_;
};

/// `adaptive` (paper Sec. 5): initial samples -> dynamic sampling (recursive splitting by the
/// local shading error, evaluating S and ∇S level by level) -> gradient reconstruction (Eq. 4)
/// -> the CPU marcher.
class AdaptiveMethod : public Method {
 public:
  AdaptiveMethod(std::string samplerType, MarchParams mp, IVec3 res, DynamicSamplingSettings ds,
                 std::unique_ptr<Sampler> sampler, std::unique_ptr<RadianceEvaluator> evaluator,
                 std::unique_ptr<Reconstruction> reconstruction)
      : samplerType_(std::move(samplerType)),
        mp_(mp),
        res_(res),
        ds_(std::move(ds)),
        sampler_(std::move(sampler)),
        evaluator_(std::move(evaluator)),
        reconstruction_(std::move(reconstruction)) {}

  RenderResult render(const Scene& scene, Progress* progress) override {
    RenderResult r;
    RenderStats& st = r.stats;
    st.method = "adaptive";
    st.backend = "cpu";
    st.device = "CPU (TBB)";
    st.width = scene.camera.width;
    st.height = scene.camera.height;
    const DensityGrid density = buildDensityVolume(scene, st);
    std::vector<RadianceSample> initial;
    {
      ScopedTimer t(st, "sampling");
      initial = sampler_->generate(scene, density);
    }
    DynamicSamplingResult ds;
    {
      ScopedTimer t(st, "dynamic_sampling");
      ds = dynamicSampling(scene, density, std::move(initial), *evaluator_, ds_);
    }
    RadianceGrid radiance(scene.medium.bounds, res_);
    ReconstructionStats rs;
    {
      ScopedTimer t(st, "reconstruction");
      rs = reconstruction_->reconstruct(scene, density, ds.samples, radiance);
    }
    r.image = marchRadianceVolume(scene, density, radiance, mp_.march, st, progress);

    st.samples = (long long)ds.samples.size();
    std::vector<long long> perLevel(ds.levels.size(), 0);
    for (const auto& s : ds.samples) ++perLevel[std::size_t(s.level)];
    Json levels = Json::array();
    for (std::size_t l = 0; l < ds.levels.size(); ++l) {
      const LevelStats& ls = ds.levels[l];
      levels.push_back({{"grid", ls.resolution},
                        {"evaluated", ls.samples},
                        {"split", ls.split},
                        {"kept", perLevel[l]},
                        {"max_error", ls.maxError},
                        {"p90_error", ls.p90Error},
                        {"ms", ls.ms}});
    }
    st.extra["samples_per_level"] = perLevel;
    st.extra["initial_samples"] = ds.levels.empty() ? 0 : ds.levels[0].samples;
    st.extra["levels"] = levels;
    st.extra["epsilon"] = ds_.epsilon;
    st.extra["tau"] = ds_.perSampleTau ? "sample" : "ancestor";
    st.extra["sampler"] = samplerType_;
    st.extra["uncovered_voxels"] = rs.uncovered;
    st.extra["radiance_resolution"] = {res_.x, res_.y, res_.z};
    st.extra["march_step"] = mp_.march.step;
    st.extra["delta1"] = mp_.delta1;
    r.samples = std::move(ds.samples);
    return r;
  }

 private:
  std::string samplerType_;
  MarchParams mp_;
  IVec3 res_;
  DynamicSamplingSettings ds_;
  std::unique_ptr<Sampler> sampler_;
  std::unique_ptr<RadianceEvaluator> evaluator_;
  std::unique_ptr<Reconstruction> reconstruction_;
};

/// The render.sampler object (default: Gaussian centres when the medium has Gaussians, else
/// 512 jittered samples); `type` receives the sampler's name.
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
