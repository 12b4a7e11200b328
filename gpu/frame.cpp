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

namespace {

/// DensityGrid::sample(p) of an uploaded density volume, from the (up to) eight voxels around
/// p read back alone (LampModel's k_l without reading the whole volume back), in the order and
/// with the clamps of Grid3::sampleIndex.
auto densityAtPoint(const Volume& v) {
  return [&v](const Vec3& p) {
    const Vec3 cell = v.bounds.extent() / Vec3(v.dims);
    const Vec3 inv = Vec3(1.0f) / cell;
    Vec3 u = (p - v.bounds.min) * inv - 0.5f;
    const Vec3 maxIndex(v.dims - 1);
    for (int a = 0; a < 3; ++a) {
      u[a] = u[a] > 0.0f ? u[a] : 0.0f;
      u[a] = u[a] < maxIndex[a] ? u[a] : maxIndex[a];
    }
    const IVec3 b = glm::min(IVec3(u), glm::max(v.dims - 2, IVec3(0)));
    const Vec3 f = u - Vec3(b);
    const IVec3 n = glm::min(v.dims - b, IVec3(2));  // 1 along a one-voxel axis
    float c[8] = {0, 0, 0, 0, 0, 0, 0, 0};
    glGetTextureSubImage(v.texture.id(), 0, b.x, b.y, b.z, n.x, n.y, n.z, GL_RED, GL_FLOAT,
                         GLsizei(sizeof c), c);
    const auto at = [&](int i, int j, int k) {
      return c[(std::min(k, n.z - 1) * n.y + std::min(j, n.y - 1)) * n.x + std::min(i, n.x - 1)];
    };
    const float c00 = at(0, 0, 0) + (at(1, 0, 0) - at(0, 0, 0)) * f.x;
    const float c10 = at(0, 1, 0) + (at(1, 1, 0) - at(0, 1, 0)) * f.x;
    const float c01 = at(0, 0, 1) + (at(1, 0, 1) - at(0, 0, 1)) * f.x;
    const float c11 = at(0, 1, 1) + (at(1, 1, 1) - at(0, 1, 1)) * f.x;
    const float c0 = c00 + (c10 - c00) * f.y;
    const float c1 = c01 + (c11 - c01) * f.y;
    return c0 + (c1 - c0) * f.z;
  };
}

}  // namespace

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
  if (settingsBounds_ && lamp_)
    bounds_ =
        lampBounds(*settingsBounds_, LampModel(scene, f.density.bounds, densityAtPoint(f.density)),
                   f.density.bounds);
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
