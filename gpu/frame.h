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

  /// Counted on the GPU from `density` (cell_occupancy.comp.glsl): every grid of a call in one
  /// pass and one read of 4 bytes per grid; each grid's bit set is kept for occupiedCellList
  /// until the next render or density. The volume is not read back.
  std::vector<long long> countOccupiedCells(std::span<const IVec3> grids) override;
  /// The grid's bits read back (cells / 8 bytes), counted first if this render has not.
  std::vector<int> occupiedCellList(IVec3 dims) override;
  /// One pass over the density volume (cell_occupancy.comp.glsl, SL_VOXEL_COUNTS) and one read
  /// of 4 bytes per cell: never the volume.
  std::vector<int> occupiedVoxelsPerCell(IVec3 dims) override;
  bool countsGridsTogether() const override { return true; }

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
  /// One pass of cell_occupancy.comp.glsl over the density volume: the grids' maps and table
  /// (dims and first word of bits per grid), their counts, and the bit sets (null with
  /// SL_VOXEL_COUNTS).
  void occupancyPass(const Program& p, const std::vector<GLint>& maps,
                     const std::vector<GLint>& table, const Buffer& counts, const Buffer* bits);
  GpuPipeline pipeline_ = GpuPipeline::Compute;
  bool splatted_ = false;
  std::vector<std::size_t> marks_;  ///< timer.count() at each sync() of this render
  std::optional<DensityGrid> host_;
  /// countOccupiedCells: the grids counted in this render, each with its first word of bits in
  /// cellBits_ (one bit per cell; cellWords_ in use).
  struct CountedGrid {
    IVec3 dims;
    std::size_t word;
  };
  std::vector<CountedGrid> countedGrids_;
  Buffer cellBits_;
  std::size_t cellWords_ = 0;
  void forgetOccupancy();
  /// The counters at the start of this render (host_waits, dispatches are differences).
  HostWaitCounts waits0_;
  PassCounts passes0_;
  std::vector<std::function<void(RenderStats&)>> deferred_;
  void startCounts();
};

}  // namespace scatterlab::gpu
