#include "core/stages.h"

#include <algorithm>

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

std::vector<int> occupiedCells(const DensityGrid& g, IVec3 dims) {
  const std::vector<int> used = occupiedVoxelsPerCell(g, dims);
  std::vector<int> out;
  for (std::size_t c = 0; c < used.size(); ++c)
    if (used[c]) out.push_back(int(c));
  return out;
}

std::vector<int> occupiedVoxelsPerCell(const DensityGrid& g, IVec3 dims) {
  const std::size_t n = std::size_t(dims.x) * std::size_t(dims.y) * std::size_t(dims.z);
  std::vector<int> used(n, 0);
  const IVec3 nd = g.dims();
  const std::vector<int> ci = voxelCells(nd.x, dims.x), cj = voxelCells(nd.y, dims.y),
                         ck = voxelCells(nd.z, dims.z);
  const float* d = g.data().data();
  for (int k = 0; k < nd.z; ++k)
    for (int j = 0; j < nd.y; ++j) {
      const std::size_t rowCell =
          std::size_t(dims.x) *
          (std::size_t(cj[std::size_t(j)]) + std::size_t(dims.y) * std::size_t(ck[std::size_t(k)]));
      for (int i = 0; i < nd.x; ++i, ++d)
        if (*d > 0.0f) ++used[rowCell + std::size_t(ci[std::size_t(i)])];
    }
  return used;
}

std::vector<RadianceSample> Sampler::generate(Frame& frame, const Scene& scene) {
  static const DensityGrid kNoDensity;
  return generate(scene, readsDensity() ? frame.hostDensity() : kNoDensity);
}

std::vector<long long> Frame::countOccupiedCells(std::span<const IVec3> grids) {
  std::vector<long long> n;
  for (const IVec3& dims : grids)
    n.push_back((long long)scatterlab::occupiedCells(hostDensity(), dims).size());
  return n;
}

std::vector<int> Frame::occupiedCellList(IVec3 dims) {
  return scatterlab::occupiedCells(hostDensity(), dims);
}

std::vector<int> Frame::occupiedVoxelsPerCell(IVec3 dims) {
  return scatterlab::occupiedVoxelsPerCell(hostDensity(), dims);
}

}  // namespace scatterlab
