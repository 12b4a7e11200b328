#include "gpu/register.h"

#include "core/method.h"
#include "core/stages.h"
#include "gpu/context.h"
#include "gpu/methods.h"
#include "gpu/stages.h"
#include "render/methods.h"
#include "render/radiance_evaluator.h"
#include "render/sampled_methods.h"
#include "sampling/dynamic_sampling.h"

namespace scatterlab::gpu {

namespace {

Interval stepRange(const Scene& scene) {
  const float ext = glm::length(scene.medium.bounds.extent());
  return Interval{ext * 1e-6, ext, true, false};
}

/// render.slicing of the GPU methods' slice marcher: "ray-steps" (default; the CPU marcher's
/// sample points, so the image matches the CPU method) or "view-planes" (the paper's slabs
/// perpendicular to the view axis).
bool parseRaySteps(Params& p) {
  return p.choice("slicing", {"ray-steps", "view-planes"}, "ray-steps") == "ray-steps";
}

SampledGpuConfig sampledConfig(Params& p, const Scene& scene, std::string note) {
  SampledGpuConfig c;
  c.mp = parseMarchParams(p, scene);
  c.radianceResolution = parseRadianceResolution(p, scene);
  c.delta2 = parseTracerSteps(p, scene).delta2;
  c.raySteps = parseRaySteps(p);
  c.sampler = makeSampler(p, scene, c.samplerType);
  c.backendNote = std::move(note);
  return c;
}

}  // namespace

std::string resolveBackend(const std::string& backend, std::string* why) {
  if (backend != "auto") return backend;
  std::string reason;
  Context* ctx = tryContext(&reason);
  if (!ctx) {
    if (why) *why = "auto: no GPU context (" + reason + "); using the CPU";
    return "cpu";
  }
  if (!ctx->info().hardware) {
    if (why)
      *why = "auto: only a software rasteriser ('" + ctx->info().renderer + "'); using the CPU";
    return "cpu";
  }
  if (why) *why = "auto: GPU '" + ctx->info().renderer + "' found; using it";
  return "gpu";
}

void registerGpuStages() {
  radianceEvaluators().add("volume-tracer-gpu", [](Params& p, const Scene& scene) {
    const float voxel = scene.medium.voxelSize();
    const float d1 = p.real("delta1", voxel, stepRange(scene));
    const float d2 = p.real("delta2", voxel, stepRange(scene));
    return std::unique_ptr<RadianceEvaluator>(new VolumeTracerGpu(d1, d2));
  });
  reconstructions().add("gradient-gpu", [](Params&, const Scene&) {
    return std::unique_ptr<Reconstruction>(new GradientSplatGpu());
  });
  reconstructions().add("per-voxel-gpu", [](Params& p, const Scene& scene) {
    const float d1 = p.real("delta1", scene.medium.voxelSize(), stepRange(scene));
    return std::unique_ptr<Reconstruction>(new PerVoxelGpu(d1));
  });
  integrators().add("slice-marcher", [](Params& p, const Scene& scene) {
    MarchSettings ms;
    ms.step = p.real("march_step", scene.medium.voxelSize(), stepRange(scene));
    const std::string slicing = p.choice("slicing", {"view-planes", "ray-steps"}, "view-planes");
    return std::unique_ptr<Integrator>(new SliceMarcher(ms, slicing == "ray-steps"));
  });

  // per-voxel: keep the CPU factory for "cpu", dispatch to the GPU method otherwise.
  const MethodFactory cpu = methods().get("per-voxel", "render.method");
  methods().add("per-voxel", [cpu](Params& p, const Scene& scene, const std::string& backend) {
    std::string note;
    const std::string b = resolveBackend(backend, &note);
    if (b == "cpu") return cpu(p, scene, "cpu");
    const MarchParams mp = parseMarchParams(p, scene);
    const IVec3 res = parseRadianceResolution(p, scene);
    return makePerVoxelGpuMethod(mp, res, parseRaySteps(p), note);
  });

  // gradient and adaptive: the same wrapping (the CPU factories stay for "cpu").
  const MethodFactory cpuGradient = methods().get("gradient", "render.method");
  methods().add("gradient",
                [cpuGradient](Params& p, const Scene& scene, const std::string& backend) {
                  std::string note;
                  if (resolveBackend(backend, &note) == "cpu") return cpuGradient(p, scene, "cpu");
                  return makeGradientGpuMethod(sampledConfig(p, scene, note));
                });
  const MethodFactory cpuAdaptive = methods().get("adaptive", "render.method");
  methods().add("adaptive",
                [cpuAdaptive](Params& p, const Scene& scene, const std::string& backend) {
                  std::string note;
                  if (resolveBackend(backend, &note) == "cpu") return cpuAdaptive(p, scene, "cpu");
                  SampledGpuConfig c = sampledConfig(p, scene, note);
                  DynamicSamplingSettings ds = parseDynamicSampling(p, scene);
                  return makeAdaptiveGpuMethod(std::move(c), std::move(ds));
                });
}

}  // namespace scatterlab::gpu
