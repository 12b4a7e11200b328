#pragma once
/// Spheres binned into the cells of a voxel grid, for the compute gathers that replace the
/// rasterised slice splats (render.gpu_pipeline = compute; docs/gpu.md): the radiance gather
/// of Eq. 4 (valid spheres of the samples) and the Gaussian density gather (culling spheres of
/// the blobs). Each bin is kBinVoxels³ voxels; its list holds every sphere that may reach one of
/// its voxel centres, in ascending sphere order, so a voxel sums its spheres in the order the
/// rasterised splat blends them (deterministic, and the same sums). Built on the host, where
/// the samples and blobs are, in O(spheres + list entries); uploaded as two storage buffers.
/// Or built on the GPU (binSpheresGpu, sphere_bins.comp.glsl), from spheres the GPU wrote.

#include <span>
#include <vector>

#include "core/math.h"
#include "gpu/gl.h"
#include "gpu/scan.h"

namespace scatterlab::gpu {

/// Voxels per bin edge.
inline constexpr int kBinVoxels = 8;

struct SphereBins {
  IVec3 bins{0};                ///< bins per axis: ceil(dims / kBinVoxels)
  std::vector<GLuint> offsets;  ///< bin b's list is items[offsets[b], offsets[b + 1])
  std::vector<GLuint> items;    ///< sphere indices
};

/// Bins spheres (xyz centre, w radius; world units) over the voxel centres of the grid of
/// `dims` voxels over `bounds`. A sphere is listed in every bin whose voxel-centre range its
/// bounding box overlaps, with one voxel of margin against rounding (the gathers test the exact
/// distance). Throws GpuError naming `pass` when the lists exceed what the device can bind
/// (GL_MAX_SHADER_STORAGE_BLOCK_SIZE), before anything is uploaded. No GL context needed
/// except for that limit (queried from the current context).
SphereBins binSpheres(std::span<const glm::vec4> spheres, const Box& bounds, IVec3 dims,
                      const char* pass);

/// The two buffers of `bins` bound at binding::kBinOffsets and kBinItems while they live.
struct BinBuffers {
  Buffer offsets, items;
  BinBuffers() = default;
  explicit BinBuffers(const SphereBins& bins);
  /// Uploads `bins` into the buffers held, re-creating one only where it is too small (with
  /// headroom: gpu::ensure). A gather reads the lists through the offsets, never past them.
  void upload(const SphereBins& bins);
  void bind() const;
};

/// Bins built on the GPU (binSpheresGpu): the lists as BinBuffers (offsets: bins + 1 uints;
/// items: the caller's item capacity of uints, the first offsets[bins] of them used), the bins
/// per axis, and the overflow word.
struct GpuBins : BinBuffers {
  IVec3 bins{0};  ///< bins per axis: ceil(dims / kBinVoxels)
  /// One uint: 0, or the list entries the spheres needed when that was more than the item
  /// capacity (the lists are then cut there: every offset clamped to the capacity, so a gather
  /// reads within them, but their sums are wrong).
  Buffer overflow;
  /// The overflow word, read back (a host wait: after the frame).
  GLuint readOverflow() const;
};

/// Bins on the GPU the first counts[countSlot] spheres of `points` (GpuSamplePoint[], at most
/// `capacity`; the count is read on the GPU, never by the host) over the voxel centres of
/// (bounds, dims): the same lists as binSpheres() (same bin ranges, each list in ascending
/// sphere order). `itemCapacity`: the most list entries the caller allows (an upper bound it
/// computed); entries past it are dropped and the overflow is recorded in the returned buffers'
/// `overflow` word (read it after the frame; non-zero = the needed total). Enqueued only: no host
/// wait; the lists are ready for storage-buffer reads (and the words for read-back) after the
/// barrier it ends with. Throws GpuError naming `pass` when `itemCapacity` entries exceed what
/// the device can bind, before any work. Uses the bindings of binding::kSamples, kBinOffsets,
/// kBinItems, kBinSphereCount, kBinCounts and kBinOverflow, and the scan's; the caller binds
/// the gather's buffers afterwards (GpuBins::bind). `previous`: the bins of an earlier frame,
/// whose buffers are reused where they are large enough (a steady frame makes none). Needs the
/// context.
GpuBins binSpheresGpu(const Buffer& points, const Buffer& counts, GLuint countSlot,
                      std::size_t capacity, const Box& bounds, IVec3 dims, std::size_t itemCapacity,
                      ScanScratch& scratch, const char* pass, GpuBins previous = {});

}  // namespace scatterlab::gpu
