#include "gpu/register.h"

#include <cstdlib>

#include "core/stages.h"
#include "gpu/context.h"
#include "gpu/dynamic_sampling.h"
#include "gpu/frame.h"
#include "gpu/light_space_march.h"
#include "gpu/radial_blur.h"
#include "gpu/reconstructions.h"
#include "gpu/screen_march.h"
#include "gpu/slice_marcher.h"
#include "gpu/tracing.h"
#include "gpu/view_march.h"
#include "gpu/volume_tracer.h"
#include "sampling/dynamic_sampling.h"
#include "shading/view_march.h"

namespace scatterlab::gpu {

namespace {

/// "dynamic" on the GPU: dynamicSamplingGpu's passes on the frame's density (the pipeline's
/// evaluator is not used: the passes trace S, ∇S and the probes themselves), in buffers kept
/// from one frame to the next. A frame whose image stays on the device with the compute gather
/// (a Renderer's, issue 33) keeps the final samples there too: the gather reads them where the
/// pass left them, and the levels' statistics are read after the frame.
class GpuRefiner : public SampleRefiner {
 public:
  GpuRefiner(DynamicSamplingSettings s, TracerSteps steps, ShadowMapSettings shadowMap)
      : s_(std::move(s)), steps_(steps), shadowMap_(shadowMap) {}
  DynamicSamplingResult refine(Frame& frame, const Scene& scene,
                               std::vector<RadianceSample> initial, RadianceEvaluator&) override {
    GpuFrame& f = static_cast<GpuFrame&>(frame);
    const ShadowMaps* shadows = f.shadowMaps(scene, shadowMap_);
    if (!(f.imageOnDevice && f.pipeline() == GpuPipeline::Compute))
      return dynamicSamplingGpu(scene, f.density, std::move(initial), steps_, s_, &f.timer, nullptr,
                                shadows, &workspace_);
    dynamicSamplingGpu(scene, f.density, std::move(initial), steps_, s_, &f.timer, nullptr, shadows,
                       &workspace_, &f.samples);
    f.deferStats([this](RenderStats& st) {
      const DynamicSamplingResult r = readDynamicSamplingGpu(workspace_, false);
      addDynamicSamplingStats(st, r, s_);
      long long n = 0;
      for (const long long c : r.finalPerLevel) n += c;
      st.samples = n;
    });
    DynamicSamplingResult r;
    r.onDevice = true;
    return r;
  }
  double tracesPerSample() const override { return 1.0 + s_.probes; }
  void setPerVoxelTraces(long long traces) override { s_.perVoxelTraces = traces; }
  void describe(RenderStats& stats, const DynamicSamplingResult& result) const override {
    addDynamicSamplingStats(stats, result, s_);
  }

 private:
  DynamicSamplingSettings s_;
  TracerSteps steps_;
  ShadowMapSettings shadowMap_;  ///< the objects' visibility at samples and probes
  DynamicSamplingWorkspace workspace_;
};

/// Backend "auto" picks the GPU only on real hardware: llvmpipe runs the GL passes on the CPU,
/// slower than the CPU variants.
bool preferGpu(std::string* why) {
  std::string reason;
  // Mesa's libEGL prints warnings (no DRI device, ...) while probing; the probe's outcome is
  // reported in `why`, so keep a CPU render quiet. A user's own EGL_LOG_LEVEL wins.
  ::setenv("EGL_LOG_LEVEL", "fatal", /*overwrite=*/0);
  Context* ctx = tryContext(&reason);
  if (!ctx) {
    *why = "auto: no GPU context (" + reason + "); using the CPU";
    return false;
  }
  if (!ctx->info().hardware) {
    *why = "auto: only a software rasteriser ('" + ctx->info().renderer + "'); using the CPU";
    return false;
  }
  *why = "auto: GPU '" + ctx->info().renderer + "' found; using it";
  return true;
}

/// What the GPU backend cannot render yet. camera.spp > 1: the compute view march takes the
/// CPU's k × k strata (view_march.comp.glsl), but the surface pass of scene objects finds one
/// surface per pixel, not per stratum, and the raster pipeline's slice marcher one ray per pixel.
std::string unsupported(const Scene& scene) {
  if (scene.camera.spp <= 1) return "";
  if (scene.objects)
    return "camera.spp > 1 is not supported on the GPU backend yet with scene objects (its "
           "surface pass finds one surface per pixel); use --backend cpu";
  const Json* pipeline = scene.render.is_object() && scene.render.contains("gpu_pipeline")
                             ? &scene.render["gpu_pipeline"]
                             : nullptr;
  if (pipeline && pipeline->is_string() && pipeline->get<std::string>() == "raster")
    return "camera.spp > 1 is not supported on the GPU backend yet with render.gpu_pipeline = "
           "\"raster\" (the slice marcher casts one ray per pixel); use the compute pipeline or "
           "--backend cpu";
  return "";
}

}  // namespace

void registerGpuStages() {
  backends()[int(Backend::Gpu)] = BackendEntry{
      [](const PipelineSettings& s) { return std::unique_ptr<Frame>(new GpuFrame(s.gpuPipeline)); },
      preferGpu, unsupported};
  radianceEvaluators().addVariant("volume-tracer", Backend::Gpu, [](const PipelineSettings& s) {
    return std::unique_ptr<RadianceEvaluator>(new VolumeTracerGpu(s.tracerSteps(), s.shadowMap));
  });
  reconstructions().addVariant("gradient", Backend::Gpu, [](const PipelineSettings& s) {
    return std::unique_ptr<Reconstruction>(
        new GradientSplatGpu(s.logValues(), s.occlusionWeights, taylorBounds(s), s.gpuPipeline,
                             s.tracerSteps().lampModel, s.tracerSteps().reach > 0.0f));
  });
  reconstructions().addVariant("per-voxel", Backend::Gpu, [](const PipelineSettings& s) {
    return std::unique_ptr<Reconstruction>(
        new PerVoxelGpu(s.delta1, s.shadowMap, s.factorLights, s.tracerSteps().lampModel));
  });
  integrators().addVariant("ray-marcher", Backend::Gpu, [](const PipelineSettings& s) {
    if (s.gpuPipeline == GpuPipeline::Compute)
      return std::unique_ptr<Integrator>(new ViewMarchGpu(s.march, s.factorLights, s.delta1,
                                                          s.shadowMap, s.tracerSteps().lampModel));
    return std::unique_ptr<Integrator>(new SliceMarcher(
        s.march, s.integratorKeys.get<RayMarcherSettings>().slicing == Slicing::RaySteps,
        s.factorLights, s.delta1, s.shadowMap, s.tracerSteps().lampModel));
  });
  integrators().addVariant("light-space-march", Backend::Gpu, [](const PipelineSettings& s) {
    return std::unique_ptr<Integrator>(new LightSpaceMarchGpu(
        s.integratorKeys.get<LightSpaceMarchSettings>(), s.delta1, s.shadowMap));
  });
  integrators().addVariant("radial-blur", Backend::Gpu, [](const PipelineSettings& s) {
    return std::unique_ptr<Integrator>(new RadialBlurGpu(s.integratorKeys.get<RadialBlurSettings>(),
                                                         s.march, s.delta1, s.shadowMap));
  });
  integrators().addVariant("jittered-march", Backend::Gpu, [](const PipelineSettings& s) {
    return std::unique_ptr<Integrator>(new JitteredMarchGpu(s));
  });
  integrators().addVariant("froxel", Backend::Gpu, [](const PipelineSettings& s) {
    return std::unique_ptr<Integrator>(new FroxelGpu(s));
  });
  refiners().addVariant("dynamic", Backend::Gpu, [](const PipelineSettings& ps) {
    return std::unique_ptr<SampleRefiner>(new GpuRefiner(
        ps.refinerKeys.get<DynamicSamplingSettings>(), ps.tracerSteps(), ps.shadowMap));
  });
}

}  // namespace scatterlab::gpu
