/// Dynamic sampling (paper Sec. 5) at 128³ on the spot-light shaft (data/scenes/shaft.json):
/// 541 requested grid samples (512 placed), ε = 1e-4, levels 16/32/64. Reports the whole
/// splitting (evaluation of S, ∇S and probes at every level, errors, splitting, scan) and the
/// time per level as counters.

#include <benchmark/benchmark.h>

#include "api/scatterlab.h"
#include "sampling/dynamic_sampling.h"

using namespace scatterlab;

namespace {

void BM_DynamicSampling_Shaft128(benchmark::State& state) {
  initialize();
  const Scene scene = loadScene(std::string(SCATTERLAB_SOURCE_DIR) + "/data/scenes/shaft.json",
                                {"render.method=adaptive", "render.paper=true", "render.epsilon=1e-4",
                                 "render.sampler={\"type\": \"grid\", \"count\": 541}",
                                 "render.probes=" + std::to_string(state.range(0))});
  Params p(scene.render, "render");
  const DynamicSamplingSettings ds = parseDynamicSampling(p, scene);
  Params sp(scene.render["sampler"], "render.sampler");
  sp.string("type");
  auto sampler = samplers().get("grid", "type")(sp, scene);
  PipelineSettings ps;
  ps.delta1 = ps.delta2 = scene.medium.voxelSize();
  auto evaluator = radianceEvaluators().get("volume-tracer", "").on[int(Backend::Cpu)](ps);
  const DensityGrid density = buildDensityVolume(scene);
  const std::vector<RadianceSample> initial = sampler->generate(scene, density);
  DynamicSamplingResult r;
  for (auto _ : state) r = dynamicSampling(scene, density, initial, *evaluator, ds);
  state.counters["samples"] = double(r.samples.size());
  for (std::size_t l = 0; l < r.levels.size(); ++l) {
    // Appended piecewise: GCC 12 reports a false -Wrestrict for "L" + std::string.
    std::string level("L");
    level += std::to_string(l);
    state.counters[level + "_evaluated"] = double(r.levels[l].samples);
    state.counters[level + "_ms"] = r.levels[l].ms;
  }
}

}  // namespace

BENCHMARK(BM_DynamicSampling_Shaft128)
    ->Arg(6)
    ->Arg(26)
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();
