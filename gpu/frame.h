#pragma once
/// The GPU backend's frame: the density and source-radiance volumes as 3D textures, the timer
/// queries of every pass, and the density read back once when a host stage (a sampler) asks
/// for it. The GL context is created when the density is first built, not by the constructor.

#include <optional>

#include "core/stages.h"
#include "gpu/stages.h"
#include "gpu/timer.h"
#include "gpu/volume.h"

namespace scatterlab::gpu {

class GpuFrame : public Frame {
 public:
  GpuFrame() = default;
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
  /// backend "gpu", device = GL_RENDERER, gpu_ms per pass, density_construction, gl_version,
  /// egl_platform.
  void report(RenderStats& stats) override;

  /// The scene objects' triangles and shadow maps, built by the first stage that needs them
  /// (SceneShadows::build; "shadow maps" in the timings).
  const ShadowMaps* shadowMaps(const Scene& scene, const ShadowMapSettings& settings) {
    return objects.build(scene, settings, &timer);
  }

  Volume density, radiance;
  StageTimer timer;
  SceneShadows objects;

 private:
  bool splatted_ = false;
  std::optional<DensityGrid> host_;
};

}  // namespace scatterlab::gpu
