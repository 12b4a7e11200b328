#pragma once
/// A frame's radiance samples on the GPU, as the volume tracer writes them and the radiance
/// gather reads them (struct of arrays, issue 33's resident frame): positions and radii
/// (GpuSamplePoint[] at binding::kSamples), S and ∇S (GpuRadianceRecord[] at
/// binding::kRadiance), and the gather's bins. The positions and the bins are kept while the
/// samples do not move (a Renderer's steady frames keep the sampler's samples), so such a frame
/// uploads nothing and bins nothing; S and ∇S are written anew by every render's tracer.

#include <optional>
#include <span>
#include <vector>

#include "core/stages.h"
#include "gpu/gl.h"
#include "gpu/scan.h"
#include "gpu/sphere_bins.h"

namespace scatterlab::gpu {

/// A sample list whose count only the GPU knows (dynamic sampling's resident pass, issue 33):
/// DeviceSamples' `points` and `radiance` hold at most `capacity` samples, the count is the uint
/// in `count`, and the bins are built on the GPU from it. `radii`: (most samples, largest
/// radius) per part of the list, from which DeviceSamples::binsFor() bounds the bins' entries.
struct DeviceSampleList {
  Buffer count;
  std::size_t capacity = 0;
  std::vector<std::pair<std::size_t, float>> radii;
};

/// The compute gather's occupied voxels no sphere covers, each with its nearest sample
/// (radiance_normalize.comp.glsl): they depend on the positions, the radii, the density and the
/// grid, not on the lights, so a frame that keeps its samples (and with them its density) fills
/// them from this list instead of searching.
struct NearestFill {
  Box bounds;
  IVec3 dims{0};
  std::size_t capacity = 0;  ///< entries `entries` holds; more: `words`[1] set, not kept
  Buffer entries;            ///< uvec2 (voxel index, sample index)
  Buffer words;              ///< uint count, uint overflow
};

struct DeviceSamples {
  std::vector<glm::vec4> spheres;  ///< what `points` holds (xyz, radius), to see a change
  Buffer points;                   ///< GpuSamplePoint[spheres.size()]
  Buffer radiance;                 ///< GpuRadianceRecord[spheres.size()]
  bool radianceCurrent = false;    ///< `radiance` was written by this render's tracer
  /// A list whose count only the GPU knows (DeviceSampleList).
  std::optional<DeviceSampleList> onDevice;
  /// The compute gather's uncovered voxels and their nearest samples (NearestFill), kept with
  /// the points. Dropped with them.
  std::optional<NearestFill> fill;

  /// Uploads the samples' positions and radii unless the same ones are uploaded already
  /// (compared on the host: no GPU wait); a new set drops the bins and S. Sizes `radiance`.
  /// Returns whether it uploaded. Ends an onDevice list. Needs the context.
  bool setPoints(std::span<const RadianceSample> samples);
  /// Makes `points` and `radiance` hold at least `capacity` samples for an onDevice list (their
  /// contents undefined), drops the bins. Needs the context.
  void reserveOnDevice(std::size_t capacity, std::vector<std::pair<std::size_t, float>> radii);
  /// The bins of the points over the voxel centres of (bounds, dims): the kept ones when they
  /// were built for this grid, else binned on the host and uploaded (once per sample set); an
  /// onDevice list is binned on the GPU (every time: its samples change with the light).
  const BinBuffers& binsFor(const Box& bounds, IVec3 dims, IVec3* binCount, const char* pass);
  /// The nearest-sample fill of (bounds, dims): the kept one, or a new empty one (`*created`
  /// true: the normalisation records it this frame). Not for an onDevice list. Needs the context.
  NearestFill& fillFor(const Box& bounds, IVec3 dims, bool* created);
  std::size_t size() const { return spheres.size(); }
  /// The overflow word of the last GPU-built bins (null: none; read it after the frame).
  const GpuBins* deviceBins() const { return deviceBins_ ? &*deviceBins_ : nullptr; }

 private:
  BinBuffers bins_;  ///< host-built bins of `spheres` (their buffers kept for the next set)
  bool binsCurrent_ = false;  ///< bins_ holds the bins of `spheres` over (binBounds_, binDims_)
  std::optional<GpuBins> deviceBins_;  ///< an onDevice list's, built each frame
  GpuBins spareBins_;                  ///< the last ones' buffers, for the next (reserveOnDevice)
  ScanScratch scratch_;                ///< the GPU binning's scan scratch
  Box binBounds_;
  IVec3 binDims_{0}, binCount_{0};
};

}  // namespace scatterlab::gpu
