#include "core/stages.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_reduce.h>

#include <algorithm>
#include <cstdint>
#include <functional>

namespace scatterlab {

const char* backendName(Backend b) {
  static constexpr std::array<const char*, kBackendCount> names = {"cpu", "gpu"};
  return names[std::size_t(b)];
}

void HostFrame::buildDensity(const Scene& scene) {
  density = std::make_shared<DensityGrid>(buildDensityVolume(scene));
}

DensityGrid buildDensityVolume(const Scene& scene) {
  DensityGrid g(scene.medium.bounds, scene.medium.resolution);
  scene.medium.density->build(g);
  return g;
}

void HostFrame::report(RenderStats& stats) {
  stats.backend = "cpu";
  stats.device = "CPU (TBB)";
  if (marchSteps) {
    stats.extra["march_steps"] = (*marchSteps)[0];
    stats.extra["march_steps_skipped"] = (*marchSteps)[1];
  }
  if (farFieldTerms) stats.extra["far_field_terms"] = *farFieldTerms;
}

std::array<BackendEntry, kBackendCount>& backends() {
  static std::array<BackendEntry, kBackendCount> b = [] {
    std::array<BackendEntry, kBackendCount> a;
    a[int(Backend::Cpu)].makeFrame = [](const PipelineSettings&) {
      return std::unique_ptr<Frame>(new HostFrame());
    };
    a[int(Backend::Cpu)].preferred = [](std::string*) { return false; };
    return a;
  }();
  return b;
}

Registry<StageFactory<Sampler>>& samplers() {
  static Registry<StageFactory<Sampler>> r("sampler");
  return r;
}
StageRegistry<EvaluatorMaker>& radianceEvaluators() {
  static StageRegistry<EvaluatorMaker> r("radiance evaluator");
  return r;
}
StageRegistry<ReconstructionMaker>& reconstructions() {
  static StageRegistry<ReconstructionMaker> r("reconstruction");
  return r;
}
StageRegistry<IntegratorMaker>& integrators() {
  static StageRegistry<IntegratorMaker> r("integrator");
  return r;
}

std::vector<int> voxelCells(int voxels, int cells) {
  std::vector<int> c(std::size_t(std::max(voxels, 0)));
  for (int u = 0; u < voxels; ++u)
    c[std::size_t(u)] = std::min(cells - 1, int((u + 0.5f) / voxels * cells));
  return c;
}

std::vector<int> cellStarts(int voxels, int cells) {
  const std::vector<int> map = voxelCells(voxels, cells);
  std::vector<int> first(std::size_t(cells) + 1, voxels);
  for (int u = voxels - 1; u >= 0; --u) first[std::size_t(map[std::size_t(u)])] = u;
  for (int c = cells - 1; c >= 0; --c)
    first[std::size_t(c)] = std::min(first[std::size_t(c)], first[std::size_t(c) + 1]);
  return first;
}

namespace {

/// Calls f(c) for every voxel centre with D > 0, c its cell's linear index in a `dims` grid
/// (occupiedCells()' map), in parallel over the layers of cells along z: the voxels of a layer
/// are a slab of whole z slices (cellStarts), so two tasks never touch one cell.
template <class F>
void forOccupiedRuns(const DensityGrid& g, IVec3 dims, const F& f) {
  const IVec3 nd = g.dims();
  const std::vector<int> ci = voxelCells(nd.x, dims.x), cj = voxelCells(nd.y, dims.y);
  const std::vector<int> z0 = cellStarts(nd.z, dims.z);
  const float* data = g.data().data();
  tbb::parallel_for(0, dims.z, [&](int cz) {
    for (int k = z0[std::size_t(cz)]; k < z0[std::size_t(cz) + 1]; ++k)
      for (int j = 0; j < nd.y; ++j) {
        const std::size_t row =
            std::size_t(dims.x) * (std::size_t(cj[std::size_t(j)]) + std::size_t(dims.y) * cz);
        const float* d = data + std::size_t(nd.x) * (std::size_t(j) + std::size_t(nd.y) * k);
        for (int i = 0; i < nd.x; ++i)
          if (d[i] > 0.0f) f(row + std::size_t(ci[std::size_t(i)]));
      }
  });
}

}  // namespace

std::vector<int> occupiedCells(const DensityGrid& g, IVec3 dims) {
  const std::vector<int> used = occupiedVoxelsPerCell(g, dims);
  std::vector<int> out;
  for (std::size_t c = 0; c < used.size(); ++c)
    if (used[c]) out.push_back(int(c));
  return out;
}

long long countOccupiedCells(const DensityGrid& g, IVec3 dims) {
  const std::vector<float>& d = g.data();
  if (dims == g.dims())  // a cell per voxel: the voxels with D > 0
    return tbb::parallel_reduce(
        tbb::blocked_range<std::size_t>(0, d.size()), 0LL,
        [&](const tbb::blocked_range<std::size_t>& r, long long n) {
          for (std::size_t i = r.begin(); i < r.end(); ++i) n += d[i] > 0.0f;
          return n;
        },
        std::plus<>());
  std::vector<std::uint8_t> used(std::size_t(dims.x) * std::size_t(dims.y) * std::size_t(dims.z));
  forOccupiedRuns(g, dims, [&](std::size_t c) { used[c] = 1; });
  return (long long)std::count(used.begin(), used.end(), std::uint8_t(1));
}

std::vector<int> occupiedVoxelsPerCell(const DensityGrid& g, IVec3 dims) {
  std::vector<int> used(std::size_t(dims.x) * std::size_t(dims.y) * std::size_t(dims.z), 0);
  forOccupiedRuns(g, dims, [&](std::size_t c) { ++used[c]; });
  return used;
}

std::vector<RadianceSample> Sampler::generate(Frame& frame, const Scene& scene) {
  static const DensityGrid kNoDensity;
  return generate(scene, readsDensity() ? frame.hostDensity() : kNoDensity);
}

std::vector<long long> Frame::countOccupiedCells(std::span<const IVec3> grids) {
  std::vector<long long> n;
  for (const IVec3& dims : grids) n.push_back(scatterlab::countOccupiedCells(hostDensity(), dims));
  return n;
}

std::vector<int> Frame::occupiedCellList(IVec3 dims) {
  return scatterlab::occupiedCells(hostDensity(), dims);
}

std::vector<int> Frame::occupiedVoxelsPerCell(IVec3 dims) {
  return scatterlab::occupiedVoxelsPerCell(hostDensity(), dims);
}

}  // namespace scatterlab
