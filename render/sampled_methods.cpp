#include "render/sampled_methods.h"

#include "core/error.h"
#include "core/stages.h"
#include "render/methods.h"
#include "render/ray_marcher.h"

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
    {
      ScopedTimer t(st, "march");
      if (progress) progress->restart("march", scene.camera.height);
      const Vec3 s = radiance.indexScale(), o = radiance.indexOffset();
      const auto lookup = [&](const Vec3& x, const Vec3&) {
        return radiance.sampleIndex(x * s + o);
      };
      r.image = marchImage(scene, density, lookup, mp_.march, progress);
    }
    st.samples = (long long)samples.size();
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

MethodFactory sampledFactory(const std::string& name) {
  return [name](Params& p, const Scene& scene, const std::string& backend) {
    if (backend == "gpu")
      throw ConfigError("method '" + name + "' has no GPU variant yet; use --backend cpu");
    const MarchParams mp = parseMarchParams(p, scene);
    const IVec3 res = parseRadianceResolution(p, scene);
    const bool hasGaussians = scene.medium.density && scene.medium.density->gaussians();
    Json defaultSampler = hasGaussians ? Json{{"type", "gaussian-centres"}}
                                       : Json{{"type", "jittered"}, {"count", 512}};
    std::unique_ptr<Sampler> sampler;
    std::string type;
    {
      const bool given = p.has("sampler");
      Params sp = given ? p.child("sampler") : Params(defaultSampler, p.keyPath("sampler"));
      if (!given) p.allow("sampler");
      type = sp.string("type", std::string(hasGaussians ? "gaussian-centres" : "jittered"));
      sampler = samplers().get(type, sp.keyPath("type"))(sp, scene);
      sp.finish();
    }
    auto evaluator = radianceEvaluators().get("volume-tracer", p.keyPath("evaluator"))(p, scene);
    auto reconstruction = reconstructions().get(name, p.keyPath("method"))(p, scene);
    return std::unique_ptr<Method>(new SampledMethod(
        name, type, mp, res, std::move(sampler), std::move(evaluator), std::move(reconstruction)));
  };
}

}  // namespace

void registerSampledMethods() {
  for (const char* name : {"gradient", "rbf", "nearest"}) methods().add(name, sampledFactory(name));
}

}  // namespace scatterlab
