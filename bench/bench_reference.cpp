/// The CPU reference renderers: `exact` at 320x240 and `per-voxel` source radiance, at 64³ and
/// 128³, on the glow demo (Gaussian smoke, one point light) and on uniform fog (every voxel
/// traced: per-voxel's worst case). Steps: one voxel (the defaults).

#include <benchmark/benchmark.h>

#include "api/scatterlab.h"
#include "cpu/per_voxel.h"

using namespace scatterlab;

namespace {

Scene loadDemo(const char* name, int resolution) {
  initialize();
  return loadScene(std::string(SCATTERLAB_SOURCE_DIR) + "/data/scenes/" + name,
                   {"medium.resolution=" + std::to_string(resolution), "render.method=exact"});
}

Scene uniformFog(int resolution) {
  initialize();
  Json doc = readJsonFile(std::string(SCATTERLAB_SOURCE_DIR) + "/data/scenes/glow.json");
  doc["medium"]["density"] = {{"type", "uniform"}, {"value", 0.5}};
  doc["medium"]["resolution"] = resolution;
  return parseScene(doc, std::string(SCATTERLAB_SOURCE_DIR) + "/data/scenes");
}

void perVoxelRadiance(benchmark::State& state, const Scene& scene) {
  const DensityGrid density = buildDensityVolume(scene);
  RadianceGrid radiance(scene.medium.bounds, scene.medium.resolution);
  PerVoxelStats pv;
  for (auto _ : state)
    pv = buildPerVoxelRadiance(scene, density, scene.medium.voxelSize(), radiance, nullptr);
  state.counters["traced_voxels"] = double(pv.traced);
  state.counters["voxels_per_s"] =
      benchmark::Counter(double(pv.traced), benchmark::Counter::kIsIterationInvariantRate);
}

void BM_PerVoxelRadiance_Glow(benchmark::State& state) {
  perVoxelRadiance(state, loadDemo("glow.json", int(state.range(0))));
}
void BM_PerVoxelRadiance_UniformFog(benchmark::State& state) {
  perVoxelRadiance(state, uniformFog(int(state.range(0))));
}

void renderMethod(benchmark::State& state, const char* method) {
  Scene scene = loadDemo("glow.json", int(state.range(0)));
  auto m = createMethod(scene, method, "cpu");
  for (auto _ : state) benchmark::DoNotOptimize(m->render(scene, nullptr));
}

void BM_Exact_Glow_320x240(benchmark::State& state) {
  renderMethod(state, "exact");
}
void BM_PerVoxel_Glow_320x240(benchmark::State& state) {
  renderMethod(state, "per-voxel");
}

}  // namespace

BENCHMARK(BM_PerVoxelRadiance_Glow)
    ->Arg(64)
    ->Arg(128)
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();
BENCHMARK(BM_PerVoxelRadiance_UniformFog)
    ->Arg(64)
    ->Arg(128)
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();
BENCHMARK(BM_Exact_Glow_320x240)->Arg(64)->Arg(128)->Unit(benchmark::kMillisecond)->UseRealTime();
BENCHMARK(BM_PerVoxel_Glow_320x240)
    ->Arg(64)
    ->Arg(128)
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();
