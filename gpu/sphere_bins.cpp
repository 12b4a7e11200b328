#include "gpu/sphere_bins.h"

#include <algorithm>
#include <cmath>
#include <string>

#include "core/error.h"
#include "gpu/bindings.h"

namespace scatterlab::gpu {

namespace {

/// The bin range [lo, hi] of the voxel centres within [c − r, c + r] along one axis, with one
/// voxel of margin; empty (lo > hi) when the sphere misses the grid.
void binRange(float c, float r, float min, float cell, int dims, int& lo, int& hi) {
  // Voxel centre i is at min + (i + 0.5)·cell.
  const float a = std::floor((c - r - min) / cell - 0.5f) - 1.0f;
  const float b = std::ceil((c + r - min) / cell - 0.5f) + 1.0f;
  if (!(b >= 0.0f) || !(a <= float(dims - 1))) {  // also false for NaN
    lo = 1;
    hi = 0;
    return;
  }
  lo = std::max(0, int(std::max(a, 0.0f))) / kBinVoxels;
  hi = std::min(dims - 1, int(std::min(b, float(dims - 1)))) / kBinVoxels;
}

std::string mib(std::size_t bytes) {
  return std::to_string((bytes + (1u << 20) - 1) >> 20) + " MiB";
}

}  // namespace

SphereBins binSpheres(std::span<const glm::vec4> spheres, const Box& bounds, IVec3 dims,
                      const char* pass) {
  SphereBins out;
  out.bins = (dims + IVec3(kBinVoxels - 1)) / kBinVoxels;
  const std::size_t nBins = std::size_t(out.bins.x) * out.bins.y * out.bins.z;
  const Vec3 cell = bounds.extent() / Vec3(dims);
  struct Range {
    IVec3 lo, hi;
  };
  std::vector<Range> ranges(spheres.size());
  std::size_t total = 0;
  for (std::size_t j = 0; j < spheres.size(); ++j) {
    const glm::vec4& s = spheres[j];
    Range& r = ranges[j];
    for (int a = 0; a < 3; ++a)
      binRange(s[a], s.w, bounds.min[a], cell[a], dims[a], r.lo[a], r.hi[a]);
    if (r.lo.x > r.hi.x || r.lo.y > r.hi.y || r.lo.z > r.hi.z || !(s.w > 0.0f)) {
      r.hi = r.lo - 1;  // empty
      continue;
    }
    total += std::size_t(r.hi.x - r.lo.x + 1) * (r.hi.y - r.lo.y + 1) * (r.hi.z - r.lo.z + 1);
  }
  // The device's limit on one storage buffer, before the lists are allocated.
  GLint64 maxBlock = 0;
  glGetInteger64v(GL_MAX_SHADER_STORAGE_BLOCK_SIZE, &maxBlock);
  const std::size_t itemBytes = total * sizeof(GLuint);
  if (total > 0xffffffffu || (maxBlock > 0 && itemBytes > std::size_t(maxBlock)))
    throw GpuError(std::string(pass) + ": the bin lists of " + std::to_string(spheres.size()) +
                   " spheres need " + mib(itemBytes) +
                   " in one storage buffer; the device allows " +
                   mib(std::size_t(std::max<GLint64>(maxBlock, 0))) +
                   " (GL_MAX_SHADER_STORAGE_BLOCK_SIZE, 32-bit offsets); use fewer or smaller "
                   "spheres (samples), a coarser volume, or render.gpu_pipeline = raster");
  std::vector<std::size_t> counts(nBins + 1, 0);
  for (const Range& r : ranges)
    for (int z = r.lo.z; z <= r.hi.z; ++z)
      for (int y = r.lo.y; y <= r.hi.y; ++y)
        for (int x = r.lo.x; x <= r.hi.x; ++x)
          ++counts[(std::size_t(z) * out.bins.y + y) * out.bins.x + x];
  // Exclusive prefix sum, then fill in ascending sphere order (a stable counting sort).
  out.offsets.resize(nBins + 1);
  std::size_t run = 0;
  for (std::size_t b = 0; b < nBins; ++b) {
    out.offsets[b] = GLuint(run);
    run += counts[b];
    counts[b] = out.offsets[b];
  }
  out.offsets[nBins] = GLuint(run);
  out.items.resize(total);
  for (std::size_t j = 0; j < spheres.size(); ++j) {
    const Range& r = ranges[j];
    for (int z = r.lo.z; z <= r.hi.z; ++z)
      for (int y = r.lo.y; y <= r.hi.y; ++y)
        for (int x = r.lo.x; x <= r.hi.x; ++x)
          out.items[counts[(std::size_t(z) * out.bins.y + y) * out.bins.x + x]++] = GLuint(j);
  }
  return out;
}

BinBuffers::BinBuffers(const SphereBins& bins)
    : offsets(bins.offsets.size() * sizeof(GLuint), bins.offsets.data(), 0, "bin offsets"),
      items(bins.items.size() * sizeof(GLuint), bins.items.data(), 0, "bin lists") {}

void BinBuffers::bind() const {
  offsets.bindBase(GL_SHADER_STORAGE_BUFFER, binding::kBinOffsets);
  items.bindBase(GL_SHADER_STORAGE_BUFFER, binding::kBinItems);
}

}  // namespace scatterlab::gpu
