#include "gpu/register.h"

#include "core/method.h"
#include "core/stages.h"
#include "gpu/context.h"
#include "gpu/methods.h"
#include "gpu/stages.h"
#include "render/methods.h"

namespace scatterlab::gpu {

namespace {

Interval stepRange(const Scene& scene) {
  const float ext = glm::length(scene.medium.bounds.extent());
  return Interval{ext * 1e-6, ext, true, false};
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
    return makePerVoxelGpuMethod(mp, parseRadianceResolution(p, scene), note);
  });
}

}  // namespace scatterlab::gpu
