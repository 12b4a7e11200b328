#pragma once
/// The GPU backend's frame: the density and source-radiance volumes as 3D textures, the timer
/// queries of every pass, and the density read back once when a host stage (a sampler) asks
/// for it. The GL context is created when the density is first built, not by the constructor.
/// A frame keeps GL object recycling on (gpu/gl.h RecyclingScope) for its lifetime: a frame
/// kept by a Renderer (Method::retainDensity) makes every later render take its textures,
/// buffers, framebuffers and queries from the objects the previous render released.

#include <functional>
#include <optional>
#include <string>
#include <vector>

#include "core/stages.h"
#include "gpu/device_samples.h"
#include "gpu/dispatch.h"
#include "gpu/timer.h"
#include "gpu/tracing.h"
#include "gpu/volume.h"

namespace scatterlab::gpu {

class GpuFrame : public Frame {
  RecyclingScope recycling_;  ///< first: outlives every GL object of the frame

 public:
  /// `pipeline`: how a density of Gaussians is built (gather or the paper's slice splat).
  explicit GpuFrame(GpuPipeline pipeline = GpuPipeline::Compute);
  /// A frame over an uploaded copy of `density` (tests; needs the context).
  explicit GpuFrame(const DensityGrid& density);

  Backend backend() const override { return Backend::Gpu; }
  /// Splats the Gaussians when the medium is a sum of Gaussians, else builds on the CPU and
  /// uploads (stats: density_construction).
  void buildDensity(const Scene& scene) override;
  const DensityGrid& hostDensity() override;
  void sync() override;
  /// Drops the pass timings and the scene objects of the previous render (the volumes stay).
  void newRender() override;
  /// backend "gpu", device = GL_RENDERER, gpu_ms per pass, gpu_timings_ms (the passes' GPU ms
  /// summed per pipeline stage of timings_ms: the passes between two sync() calls belong to the
  /// stage that ended with the second), gpu_ms_total, density_construction, gl_version,
  /// egl_platform; host_waits (how many times the host blocked on the GPU in this render, the
  /// image read-back aside), image_readback_ms (when the image was read back), dispatches and
  /// indirect_dispatches (compute dispatches of this render), and the deferred stats.
  /// (On llvmpipe "GPU ms" are CPU time of the software rasteriser.)
  void report(RenderStats& stats) override;

  /// Statistics that would make the host wait if read now (counts the GPU writes): `read`
  /// fills them into the stats in report(), after the frame.
  void deferStats(std::function<void(RenderStats&)> read) { deferred_.push_back(std::move(read)); }

  /// The scene objects' triangles and shadow maps, built by the first stage that needs them
  /// (SceneShadows::build; "shadow maps" in the timings).
  const ShadowMaps* shadowMaps(const Scene& scene, const ShadowMapSettings& settings) {
    return objects.build(scene, settings, &timer);
  }

  /// Counted on the GPU from `density` (cell_occupancy.comp.glsl): a 4-byte read per call, and
  /// for `list` the grid's stamps; the volume is not read back.
  long long occupiedCells(IVec3 dims, std::vector<int>* list) override;

  void keepImageOnDevice(bool on) override { imageOnDevice = on; }
  std::optional<std::array<unsigned, 3>> deviceImage() const override;

  Volume density, radiance;
  /// The samples on the GPU (gpu/device_samples.h): positions and bins kept across renders
  /// while the samples do not move, S and ∇S written by each render's tracer.
  DeviceSamples samples;
  GpuPipeline pipeline() const { return pipeline_; }
  /// Method::imageOnDevice: the compute view march leaves its image in `image` (RGBA32F, alpha
  /// = the image's alpha) and returns an empty Image.
  bool imageOnDevice = false;
  Texture image;
  int imageWidth = 0, imageHeight = 0;
  StageTimer timer;
  SceneShadows objects;

 private:
  GpuPipeline pipeline_ = GpuPipeline::Compute;
  bool splatted_ = false;
  std::vector<std::size_t> marks_;  ///< timer.count() at each sync() of this render
  std::optional<DensityGrid> host_;
  Buffer cellStamps_;  ///< occupiedCells: uint per cell, the last call's token
  std::uint32_t cellToken_ = 0;
  /// The counters at the start of this render (host_waits, dispatches are differences).
  HostWaitCounts waits0_;
  PassCounts passes0_;
  std::vector<std::function<void(RenderStats&)>> deferred_;
  void startCounts();
};

}  // namespace scatterlab::gpu
