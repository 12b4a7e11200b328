#include "gpu/frame.h"

#include "gpu/context.h"
#include "gpu/stages.h"

namespace scatterlab::gpu {

GpuFrame::GpuFrame(const DensityGrid& d) : density(uploadDensity(d)) {}

void GpuFrame::buildDensity(const Scene& scene) {
  context();  // current before the first timer query or upload
  density = gpu::buildDensity(scene, &timer, &splatted_);
  host_.reset();
}

const DensityGrid& GpuFrame::hostDensity() {
  if (!host_) host_ = readDensity(density);
  return *host_;
}

void GpuFrame::newRender() {
  context();  // the queries are deleted in the frame's context
  timer = StageTimer();
  objects = SceneShadows();
}

void GpuFrame::sync() {
  glFinish();
}

void GpuFrame::report(RenderStats& st) {
  const Context& ctx = context();
  st.backend = "gpu";
  st.device = ctx.info().renderer;
  Json gpuMs = Json::object();
  for (const auto& [stage, ms] : timer.results()) gpuMs[stage] = ms;
  st.extra["gpu_ms"] = gpuMs;
  st.extra["density_construction"] = splatted_ ? "gpu splat" : "cpu build + upload";
  st.extra["gl_version"] = ctx.info().version;
  st.extra["egl_platform"] = ctx.info().platform;
  if (objects.maps) {
    const ShadowMapSettings& sm = objects.maps->settings();
    st.extra["shadow_map"] = {{"type", sm.type == ShadowMapSettings::Type::Vsm ? "vsm" : "depth"},
                              {"resolution", sm.resolution},
                              {"layers", objects.maps->layers()}};
  }
}

// The stages' frame overrides: the passes on the frame's volumes, timed into its timer.

void VolumeTracerGpu::evaluate(Frame& frame, const Scene& scene, std::span<RadianceSample> samples,
                               bool gradients) {
  GpuFrame& f = static_cast<GpuFrame&>(frame);
  const ShadowMaps* shadows = f.shadowMaps(scene, shadowMap_);
  evaluate(scene, f.density, samples, gradients, &f.timer, shadows);
}

ReconstructionStats GradientSplatGpu::reconstruct(Frame& frame, const Scene& scene,
                                                  std::span<const RadianceSample> samples,
                                                  IVec3 dims, Progress*) {
  GpuFrame& f = static_cast<GpuFrame&>(frame);
  ReconstructionStats st;
  sigmaT_ = scene.medium.sigmaT;
  f.radiance = reconstruct(f.density, samples, scene.medium.bounds, dims, &st, &f.timer);
  return st;
}

ReconstructionStats PerVoxelGpu::reconstruct(Frame& frame, const Scene& scene,
                                             std::span<const RadianceSample>, IVec3 dims,
                                             Progress*) {
  GpuFrame& f = static_cast<GpuFrame&>(frame);
  ReconstructionStats st;
  const ShadowMaps* shadows = f.shadowMaps(scene, shadowMap_);
  f.radiance = build(scene, f.density, scene.medium.bounds, dims, &st, &f.timer, shadows);
  return st;
}

Image SliceMarcher::integrate(Frame& frame, const Scene& scene, Progress*) {
  GpuFrame& f = static_cast<GpuFrame&>(frame);
  f.shadowMaps(scene, shadowMap_);
  return integrate(scene, f.density, f.radiance, &f.timer, &slices_, &f.objects);
}

void SliceMarcher::describe(RenderStats& st) const {
  st.extra["slicing"] = raySteps_ ? "ray-steps" : "view-planes";
  st.extra["slices"] = slices_;
}

}  // namespace scatterlab::gpu
