#include "gpu/methods.h"

#include "gpu/context.h"
#include "gpu/dynamic_sampling.h"
#include "gpu/stages.h"
#include "gpu/timer.h"
#include "gpu/volume.h"

namespace scatterlab::gpu {

namespace {

/// Stats every GPU method reports. Needs a current context.
void commonStats(RenderStats& st, const char* method, const Scene& scene, const Context& ctx) {
  st.method = method;
  st.backend = "gpu";
  st.device = ctx.info().renderer;
  st.width = scene.camera.width;
  st.height = scene.camera.height;
}

void finishStats(RenderStats& st, StageTimer& timer, const Context& ctx, const MarchParams& mp,
                 IVec3 res, bool splatted, bool raySteps, int slices, const std::string& note) {
  Json gpuMs = Json::object();
  for (const auto& [stage, ms] : timer.results()) gpuMs[stage] = ms;
  st.extra["gpu_ms"] = gpuMs;
  st.extra["density_construction"] = splatted ? "gpu splat" : "cpu build + upload";
  st.extra["radiance_resolution"] = {res.x, res.y, res.z};
  st.extra["march_step"] = mp.march.step;
  st.extra["delta1"] = mp.delta1;
  st.extra["slicing"] = raySteps ? "ray-steps" : "view-planes";
  st.extra["slices"] = slices;
  st.extra["gl_version"] = ctx.info().version;
  st.extra["egl_platform"] = ctx.info().platform;
  if (!note.empty()) st.extra["backend_choice"] = note;
}

class PerVoxelGpuMethod : public Method {
 public:
  PerVoxelGpuMethod(MarchParams mp, IVec3 res, bool raySteps, std::string note)
      : mp_(mp), res_(res), raySteps_(raySteps), note_(std::move(note)) {}

  RenderResult render(const Scene& scene, Progress*) override {
    Context& ctx = context();
    RenderResult r;
    RenderStats& st = r.stats;
    commonStats(st, "per-voxel", scene, ctx);
    StageTimer timer;
    Volume density, radiance;
    bool splatted = false;
    PerVoxelStats pv;
    // Wall times per stage end with glFinish so that they are the GPU's work, not queueing.
    {
      ScopedTimer t(st, "density");
      density = buildDensity(scene, &timer, &splatted);
      glFinish();
    }
    {
      ScopedTimer t(st, "radiance");
      radiance =
          PerVoxelGpu(mp_.delta1).build(scene, density, scene.medium.bounds, res_, &pv, &timer);
      glFinish();
    }
    int slices = 0;
    {
      ScopedTimer t(st, "march");
      r.image =
          SliceMarcher(mp_.march, raySteps_).integrate(scene, density, radiance, &timer, &slices);
    }
    st.extra["traced_voxels"] = pv.traced;
    st.extra["empty_voxels"] = pv.skipped;
    finishStats(st, timer, ctx, mp_, res_, splatted, raySteps_, slices, note_);
    return r;
  }

 private:
  MarchParams mp_;
  IVec3 res_;
  bool raySteps_;
  std::string note_;
};

/// gradient (settings empty) or adaptive (with dynamic sampling settings).
class SampledGpuMethod : public Method {
 public:
  SampledGpuMethod(SampledGpuConfig c, std::optional<DynamicSamplingSettings> ds)
      : c_(std::move(c)), ds_(std::move(ds)) {}

  RenderResult render(const Scene& scene, Progress*) override {
    Context& ctx = context();
    RenderResult r;
    RenderStats& st = r.stats;
    const bool adaptive = ds_.has_value();
    commonStats(st, adaptive ? "adaptive" : "gradient", scene, ctx);
    StageTimer timer;
    Volume density;
    bool splatted = false;
    {
      ScopedTimer t(st, "density");
      density = buildDensity(scene, &timer, &splatted);
      glFinish();
    }
    std::vector<RadianceSample> samples;
    {
      // The samplers run on the CPU and may look at the density: read it back.
      ScopedTimer t(st, "sampling");
      const DensityGrid hostDensity = readDensity(density);
      samples = c_.sampler->generate(scene, hostDensity);
    }
    DynamicSamplingResult dsr;
    if (adaptive) {
      ScopedTimer t(st, "dynamic_sampling");
      dsr = dynamicSamplingGpu(scene, density, std::move(samples), {c_.mp.delta1, c_.delta2}, *ds_,
                               &timer);
      samples = dsr.samples;
      glFinish();
    } else {
      ScopedTimer t(st, "evaluation");
      VolumeTracerGpu(c_.mp.delta1, c_.delta2)
          .evaluate(scene, density, samples, /*gradients=*/true, &timer);
      glFinish();
    }
    Volume radiance;
    ReconstructionStats rs;
    {
      ScopedTimer t(st, "reconstruction");
      radiance = GradientSplatGpu().reconstruct(density, samples, scene.medium.bounds,
                                                c_.radianceResolution, &rs, &timer);
      glFinish();
    }
    int slices = 0;
    {
      ScopedTimer t(st, "march");
      r.image = SliceMarcher(c_.mp.march, c_.raySteps)
                    .integrate(scene, density, radiance, &timer, &slices);
    }
    st.samples = (long long)samples.size();
    st.extra["sampler"] = c_.samplerType;
    st.extra["uncovered_voxels"] = rs.uncovered;
    if (adaptive) addDynamicSamplingStats(st, dsr.levels, samples, *ds_);
    finishStats(st, timer, ctx, c_.mp, c_.radianceResolution, splatted, c_.raySteps, slices,
                c_.backendNote);
    r.samples = std::move(samples);
    return r;
  }

 private:
  SampledGpuConfig c_;
  std::optional<DynamicSamplingSettings> ds_;
};

}  // namespace

std::unique_ptr<Method> makePerVoxelGpuMethod(const MarchParams& mp, IVec3 res, bool raySteps,
                                              std::string note) {
  return std::make_unique<PerVoxelGpuMethod>(mp, res, raySteps, std::move(note));
}

std::unique_ptr<Method> makeGradientGpuMethod(SampledGpuConfig config) {
  return std::make_unique<SampledGpuMethod>(std::move(config), std::nullopt);
}

std::unique_ptr<Method> makeAdaptiveGpuMethod(SampledGpuConfig config,
                                              DynamicSamplingSettings settings) {
  return std::make_unique<SampledGpuMethod>(std::move(config), std::move(settings));
}

}  // namespace scatterlab::gpu
