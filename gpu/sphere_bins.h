#pragma once
/// Spheres binned into the cells of a voxel grid, for the compute gathers that replace the
/// rasterised slice splats (render.gpu_pipeline = compute; docs/gpu.md): the radiance gather
/// of Eq. 4 (valid spheres of the samples) and the Gaussian density gather (culling spheres of
/// the blobs). Each bin is kBinVoxels³ voxels; its list holds every sphere that may reach one of
/// its voxel centres, in ascending sphere order, so a voxel sums its spheres in the order the
/// rasterised splat blends them (deterministic, and the same sums). Built on the host, where
/// the samples and blobs are, in O(spheres + list entries); uploaded as two storage buffers.

#include <span>
#include <vector>

#include "core/math.h"
#include "gpu/gl.h"

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
  explicit BinBuffers(const SphereBins& bins);
  void bind() const;
};

}  // namespace scatterlab::gpu
