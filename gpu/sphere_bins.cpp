#include "gpu/sphere_bins.h"

#include <algorithm>
#include <cmath>
#include <string>

#include "core/error.h"
#include "gpu/bindings.h"
#include "gpu/dispatch.h"
#include "gpu/shaders.h"

namespace scatterlab::gpu {

namespace {

/// The reciprocal of the grid's voxel edges, computed once on the host: the bins are found by
/// multiplying with it, because a float product rounds alike on every IEEE device, where a GPU's
/// division may be off by an ulp or two (NVIDIA's) and move a bin boundary.
Vec3 binInvCell(const Box& bounds, const IVec3& dims) {
  return Vec3(1.0f) / (bounds.extent() / Vec3(dims));
}

/// The bin range [lo, hi] of the voxel centres within [c − r, c + r] along one axis, with one
/// voxel of margin; empty (lo > hi) when the sphere misses the grid.
void binRange(float c, float r, float min, float invCell, int dims, int& lo, int& hi) {
  // Voxel centre i is at min + (i + 0.5)·cell.
  const float a = std::floor((c - r - min) * invCell - 0.5f) - 1.0f;
  const float b = std::ceil((c + r - min) * invCell - 0.5f) + 1.0f;
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

/// Throws GpuError naming `pass` when `entries` list entries (`what`: whose) do not fit one
/// storage buffer of the device (GL_MAX_SHADER_STORAGE_BLOCK_SIZE) or 32-bit offsets.
void checkListSize(std::size_t entries, const std::string& what, const char* pass) {
  const std::size_t maxBlock = maxStorageBlock();
  const std::size_t itemBytes = entries * sizeof(GLuint);
  if (entries > 0xffffffffu || itemBytes > maxBlock)
    throw GpuError(std::string(pass) + ": " + what + " need " + mib(itemBytes) +
                   " in one storage buffer; the device allows " + mib(maxBlock) +
                   " (GL_MAX_SHADER_STORAGE_BLOCK_SIZE, 32-bit offsets); use fewer or smaller "
                   "spheres (samples), a coarser volume, or render.gpu_pipeline = raster");
}

/// A pass of sphere_bins.comp.glsl (SL_BINS_COUNT, SL_BINS_FILL or SL_BINS_SORT).
const Program& binsProgram(const char* variant, const char* label) {
  return program({.compute = {"sphere_bins.comp.glsl"}, .defines = {variant}}, label);
}

/// The count and fill passes' inputs: the spheres and their count, the grid, the per-bin counts.
void bindSpherePass(const Program& p, const Buffer& points, const Buffer& counts, GLuint countSlot,
                    std::size_t capacity, const Box& bounds, IVec3 dims, IVec3 bins,
                    const Buffer& binCounts) {
  p.use();
  glUniform1ui(p.uniform("uCountSlot"), countSlot);
  glUniform1ui(p.uniform("uCapacity"), GLuint(std::min<std::size_t>(capacity, 0xffffffffu)));
  setVec3(p, "uGridMin", bounds.min);
  setVec3(p, "uGridInvCell", binInvCell(bounds, dims));  // binSpheres', to the bit
  setIVec3(p, "uGridDims", dims);
  setIVec3(p, "uBins", bins);
  glUniform1i(p.uniform("uBinVoxels"), kBinVoxels);
  points.bindBase(GL_SHADER_STORAGE_BUFFER, binding::kSamples);
  counts.bindBase(GL_SHADER_STORAGE_BUFFER, binding::kBinSphereCount);
  binCounts.bindBase(GL_SHADER_STORAGE_BUFFER, binding::kBinCounts);
}

}  // namespace

SphereBins binSpheres(std::span<const glm::vec4> spheres, const Box& bounds, IVec3 dims,
                      const char* pass) {
  SphereBins out;
  out.bins = (dims + IVec3(kBinVoxels - 1)) / kBinVoxels;
  const std::size_t nBins = std::size_t(out.bins.x) * out.bins.y * out.bins.z;
  const Vec3 invCell = binInvCell(bounds, dims);
  struct Range {
    IVec3 lo, hi;
  };
  std::vector<Range> ranges(spheres.size());
  std::size_t total = 0;
  for (std::size_t j = 0; j < spheres.size(); ++j) {
    const glm::vec4& s = spheres[j];
    Range& r = ranges[j];
    for (int a = 0; a < 3; ++a)
      binRange(s[a], s.w, bounds.min[a], invCell[a], dims[a], r.lo[a], r.hi[a]);
    if (r.lo.x > r.hi.x || r.lo.y > r.hi.y || r.lo.z > r.hi.z || !(s.w > 0.0f)) {
      r.hi = r.lo - 1;  // empty
      continue;
    }
    total += std::size_t(r.hi.x - r.lo.x + 1) * (r.hi.y - r.lo.y + 1) * (r.hi.z - r.lo.z + 1);
  }
  // The device's limit on one storage buffer, before the lists are allocated.
  checkListSize(total, "the bin lists of " + std::to_string(spheres.size()) + " spheres", pass);
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

BinBuffers::BinBuffers(const SphereBins& bins) {
  upload(bins);
}

void BinBuffers::upload(const SphereBins& bins) {
  const auto put = [](Buffer& b, const std::vector<GLuint>& v, const char* label) {
    ensure(b, v.size() * sizeof(GLuint), label, Growth::Varies);
    if (!v.empty())
      glNamedBufferSubData(b.id(), 0, GLsizeiptr(v.size() * sizeof(GLuint)), v.data());
  };
  put(offsets, bins.offsets, "bin offsets");
  put(items, bins.items, "bin lists");
}

void BinBuffers::bind() const {
  offsets.bindBase(GL_SHADER_STORAGE_BUFFER, binding::kBinOffsets);
  items.bindBase(GL_SHADER_STORAGE_BUFFER, binding::kBinItems);
}

GLuint GpuBins::readOverflow() const {
  GLuint words = 0;
  overflow.read(&words, sizeof words);
  return words;
}

GpuBins binSpheresGpu(const Buffer& points, const Buffer& counts, GLuint countSlot,
                      std::size_t capacity, const Box& bounds, IVec3 dims, std::size_t itemCapacity,
                      ScanScratch& scratch, const char* pass, GpuBins previous) {
  checkListSize(itemCapacity,
                "the bin lists' capacity of " + std::to_string(itemCapacity) + " entries", pass);
  GpuBins out = std::move(previous);
  out.bins = (dims + IVec3(kBinVoxels - 1)) / kBinVoxels;
  const std::size_t nBins = std::size_t(out.bins.x) * out.bins.y * out.bins.z;
  const GLuint zero = 0;
  // Every offset and every entry read later is written below: the previous buffers serve where
  // they are large enough (the lists' bound follows the sample count: Growth::Varies).
  ensure(out.offsets, (nBins + 1) * sizeof(GLuint), "bin offsets");
  ensure(out.items, itemCapacity * sizeof(GLuint), "bin lists", Growth::Varies);
  ensure(out.overflow, sizeof(GLuint), "bin overflow");
  glClearNamedBufferData(out.overflow.id(), GL_R32UI, GL_RED_INTEGER, GL_UNSIGNED_INT, &zero);
  // Per bin the entries counted, then the slots the fill has yet to take; one more, left at 0,
  // so that the scan's last offset is the total.
  Buffer binCounts((nBins + 1) * sizeof(GLuint), nullptr, 0, "bin counts");
  glClearNamedBufferData(binCounts.id(), GL_R32UI, GL_RED_INTEGER, GL_UNSIGNED_INT, &zero);
  glMemoryBarrier(GL_SHADER_STORAGE_BARRIER_BIT | GL_BUFFER_UPDATE_BARRIER_BIT);

  // One invocation per sphere slot up to the capacity (those past the count return), the
  // workgroups in 2D past GL's least limit of 65535 per axis.
  const GLuint sphereGroups = groups(capacity, 64);
  const UVec3 perSphere = sphereGroups <= 65535u ? UVec3(sphereGroups, 1, 1)
                                                 : UVec3(65535u, groups(sphereGroups, 65535u), 1);
  const Program& count = binsProgram("SL_BINS_COUNT", "sphere bins (count)");
  bindSpherePass(count, points, counts, countSlot, capacity, bounds, dims, out.bins, binCounts);
  dispatch("sphere bins (count)", perSphere);
  glMemoryBarrier(GL_SHADER_STORAGE_BARRIER_BIT);

  scanBuffer(binCounts, out.offsets, GLuint(nBins + 1), false, scratch);

  const Program& fill = binsProgram("SL_BINS_FILL", "sphere bins (fill)");
  bindSpherePass(fill, points, counts, countSlot, capacity, bounds, dims, out.bins, binCounts);
  glUniform1ui(fill.uniform("uItemCapacity"), GLuint(itemCapacity));
  out.offsets.bindBase(GL_SHADER_STORAGE_BUFFER, binding::kBinOffsets);
  out.items.bindBase(GL_SHADER_STORAGE_BUFFER, binding::kBinItems);
  out.overflow.bindBase(GL_SHADER_STORAGE_BUFFER, binding::kBinOverflow);
  dispatch("sphere bins (fill)", perSphere);
  glMemoryBarrier(GL_SHADER_STORAGE_BARRIER_BIT);

  // One workgroup per bin.
  const Program& sort = binsProgram("SL_BINS_SORT", "sphere bins (sort)");
  sort.use();
  glUniform1ui(sort.uniform("uItemCapacity"), GLuint(itemCapacity));
  setIVec3(sort, "uBins", out.bins);
  out.offsets.bindBase(GL_SHADER_STORAGE_BUFFER, binding::kBinOffsets);
  out.items.bindBase(GL_SHADER_STORAGE_BUFFER, binding::kBinItems);
  dispatch("sphere bins (sort)", UVec3(out.bins));
  glMemoryBarrier(GL_SHADER_STORAGE_BARRIER_BIT | GL_BUFFER_UPDATE_BARRIER_BIT);
  return out;
}

}  // namespace scatterlab::gpu
