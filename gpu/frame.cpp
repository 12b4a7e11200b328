#include "gpu/frame.h"

#include "gpu/context.h"
#include "gpu/stages.h"
#include "shading/transport.h"

namespace scatterlab::gpu {

GpuFrame::GpuFrame(const DensityGrid& d) : density(uploadDensity(d)) {}

void GpuFrame::buildDensity(const Scene& scene) {
  context();  // current before the first timer query or upload
  density = Volume();
  density = gpu::buildDensity(scene, &timer, &splatted_, pipeline_);
  host_.reset();
}

const DensityGrid& GpuFrame::hostDensity() {
  if (!host_) {
    ScopedGpuTimer t(&timer, "density read-back");
    host_ = readDensity(density);
  }
  return *host_;
}

void GpuFrame::newRender() {
  context();  // the queries are deleted in the frame's context
  timer = StageTimer();
  objects = SceneShadows();
  image = Texture();
  marks_.clear();
}

std::optional<std::array<unsigned, 3>> GpuFrame::deviceImage() const {
  if (!imageOnDevice || !image) return std::nullopt;
  return std::array<unsigned, 3>{image.id(), unsigned(imageWidth), unsigned(imageHeight)};
}

void GpuFrame::sync() {
  glFinish();
  marks_.push_back(timer.count());
}

void GpuFrame::report(RenderStats& st) {
  const Context& ctx = context();
  st.backend = "gpu";
  st.device = ctx.info().renderer;
  const std::vector<std::pair<std::string, double>> spans = timer.spans();
  Json gpuMs = Json::object();
  double total = 0.0;
  for (const auto& [pass, ms] : spans) {
    gpuMs[pass] = gpuMs.value(pass, 0.0) + ms;
    total += ms;
  }
  st.extra["gpu_ms"] = gpuMs;
  st.extra["gpu_ms_total"] = total;
  // One sync() per pipeline stage, in the order of timings_ms (methods/pipeline.cpp): each pass
  // belongs to the first stage whose sync came after it began.
  if (!marks_.empty() && marks_.size() == st.timingsMs.size()) {
    Json byStage = Json::object();
    std::size_t k = 0;
    for (std::size_t i = 0; i < spans.size(); ++i) {
      while (k < marks_.size() && marks_[k] <= i) ++k;
      const std::string& stage = k < marks_.size() ? st.timingsMs[k].first : "after march";
      byStage[stage] = byStage.value(stage, 0.0) + spans[i].second;
    }
    st.extra["gpu_ms_by_stage"] = byStage;
  }
  marks_.clear();
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
  if (settingsBounds_ && lamp_) bounds_ = lampBounds(*settingsBounds_, scene, f.hostDensity());
  f.radiance = Volume();  // the previous render's volume goes back to the recycler first
  f.radiance = reconstruct(f.density, samples, scene.medium.bounds, dims, &st, &f.timer);
  return st;
}

ReconstructionStats PerVoxelGpu::reconstruct(Frame& frame, const Scene& scene,
                                             std::span<const RadianceSample>, IVec3 dims,
                                             Progress*) {
  GpuFrame& f = static_cast<GpuFrame&>(frame);
  ReconstructionStats st;
  const ShadowMaps* shadows = f.shadowMaps(scene, shadowMap_);
  f.radiance = Volume();
  f.radiance = build(scene, f.density, scene.medium.bounds, dims, &st, &f.timer, shadows);
  return st;
}

Image SliceMarcher::integrate(Frame& frame, const Scene& scene, Progress*) {
  GpuFrame& f = static_cast<GpuFrame&>(frame);
  f.shadowMaps(scene, shadowMap_);
  return integrate(scene, f.density, f.radiance, &f.timer, &slices_, &f.objects);
}

void SliceMarcher::describe(RenderStats& st) const {
  st.extra["gpu_pipeline"] = "raster";
  st.extra["slicing"] = raySteps_ ? "ray-steps" : "view-planes";
  st.extra["slices"] = slices_;
}

}  // namespace scatterlab::gpu
