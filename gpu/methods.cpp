#include "gpu/methods.h"

#include "gpu/context.h"
#include "gpu/stages.h"
#include "gpu/timer.h"
#include "gpu/volume.h"

namespace scatterlab::gpu {

namespace {

class PerVoxelGpuMethod : public Method {
 public:
  PerVoxelGpuMethod(MarchParams mp, IVec3 res, std::string note)
      : mp_(mp), res_(res), note_(std::move(note)) {}

  RenderResult render(const Scene& scene, Progress*) override {
    Context& ctx = context();
    RenderResult r;
    RenderStats& st = r.stats;
    st.method = "per-voxel";
    st.backend = "gpu";
    st.device = ctx.info().renderer;
    st.width = scene.camera.width;
    st.height = scene.camera.height;
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
      r.image = SliceMarcher(mp_.march).integrate(scene, density, radiance, &timer, &slices);
    }
    Json gpuMs = Json::object();
    for (const auto& [stage, ms] : timer.results()) gpuMs[stage] = ms;
    st.extra["gpu_ms"] = gpuMs;
    st.extra["density_construction"] = splatted ? "gpu splat" : "cpu build + upload";
    st.extra["traced_voxels"] = pv.traced;
    st.extra["empty_voxels"] = pv.skipped;
    st.extra["radiance_resolution"] = {res_.x, res_.y, res_.z};
    st.extra["march_step"] = mp_.march.step;
    st.extra["delta1"] = mp_.delta1;
    st.extra["slices"] = slices;
    st.extra["gl_version"] = ctx.info().version;
    st.extra["egl_platform"] = ctx.info().platform;
    if (!note_.empty()) st.extra["backend_choice"] = note_;
    return r;
  }

 private:
  MarchParams mp_;
  IVec3 res_;
  std::string note_;
};

}  // namespace

std::unique_ptr<Method> makePerVoxelGpuMethod(const MarchParams& mp, IVec3 res, std::string note) {
  return std::make_unique<PerVoxelGpuMethod>(mp, res, std::move(note));
}

}  // namespace scatterlab::gpu
