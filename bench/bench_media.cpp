// Media benchmarks (issue 3): fitting smoke1.vdb with 512 Gaussians, density splatting at 128³,
// and the model's memory against the dense grid. Results: docs/benchmarks.md, "Media (issue 3)".

#include <benchmark/benchmark.h>

#include "media/sog.h"
#include "media/sog_fit.h"
#include "media/vdb.h"

namespace {

using namespace scatterlab;

const DensityGrid& smoke() {
  static const DensityGrid g =
      loadVdbAsDense(SCATTERLAB_SOURCE_DIR "/data/vdb/smoke1.vdb", "density");
  return g;
}

const SogModel& fitted() {
  static const SogModel m = [] {
    SogFitOptions o;
    o.gaussians = 512;
    return fitSog(smoke(), o);
  }();
  return m;
}

void BM_FitSmoke1_512(benchmark::State& state) {
  SogFitReport rep;
  for (auto _ : state) {
    SogFitOptions o;
    o.gaussians = 512;
    benchmark::DoNotOptimize(fitSog(smoke(), o, &rep));
  }
  state.counters["gaussians"] = rep.gaussians;
  state.counters["hash_entries"] = double(rep.hashEntries);
  state.counters["relL2_gaussians"] = rep.relL2Gaussians;
  state.counters["relL2_model"] = rep.relL2Model;
}
BENCHMARK(BM_FitSmoke1_512)->Unit(benchmark::kSecond)->Iterations(1);

void BM_SplatSmoke1_128(benchmark::State& state) {
  const SogModel& m = fitted();
  const bool residual = state.range(0) != 0;
  DensityGrid g(m.residual.bounds(), IVec3(128));
  for (auto _ : state) {
    m.splat(g, residual);
    benchmark::DoNotOptimize(g.data().data());
  }
  state.SetLabel(residual ? "gaussians + residual" : "gaussians only");
}
BENCHMARK(BM_SplatSmoke1_128)->Arg(0)->Arg(1)->Unit(benchmark::kMillisecond);

void BM_ModelMemory(benchmark::State& state) {
  const SogModel& m = fitted();
  for (auto _ : state) benchmark::DoNotOptimize(m.fileBytes());
  state.counters["dense_bytes"] = double(smoke().size() * sizeof(float));
  state.counters["sog_file_bytes"] = double(m.fileBytes());
  state.counters["sog_memory_bytes"] =
      double(m.gaussians.size() * sizeof(GaussianBlob) + m.residual.memoryBytes());
  state.counters["hash_entries"] = double(m.residual.size());
}
BENCHMARK(BM_ModelMemory)->Iterations(1);

}  // namespace
