// Issue 4: building the 128^3 source-radiance volume of the Fig. 3 scene (data/scenes/fig3.json)
// with `gradient` from N jittered samples (sampling + volume-traced S and ∇S + Eq. 4 gather)
// versus `per-voxel` (S traced at every occupied voxel). Density volume built once, outside.
//   build/bin/scatterlab_bench --benchmark_filter='Interp' --benchmark_min_time=1x

#include <benchmark/benchmark.h>

#include "api/scatterlab.h"
#include "core/stages.h"
#include "cpu/interpolation.h"
#include "cpu/per_voxel.h"
#include "cpu/radiance_evaluator.h"

namespace scatterlab {
namespace {

struct Fixture {
  Scene scene;
  DensityGrid density;
  Fixture() {
    initialize();
    scene = loadScene(SCATTERLAB_SOURCE_DIR "/data/scenes/fig3.json");
    density = buildDensityVolume(scene);
  }
  static Fixture& get() {
    static Fixture f;
    return f;
  }
};

void BM_InterpPerVoxel128(benchmark::State& state) {
  Fixture& f = Fixture::get();
  RadianceGrid out(f.scene.medium.bounds, IVec3(128));
  for (auto _ : state) {
    buildPerVoxelRadiance(f.scene, f.density, f.scene.medium.voxelSize(), out, nullptr);
    benchmark::DoNotOptimize(out.data().data());
  }
}
BENCHMARK(BM_InterpPerVoxel128)
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime()
    ->MeasureProcessCPUTime();

/// Positions and radii from the named sampler (`count` omitted when 0: all Gaussian centres).
std::vector<RadianceSample> samplesOf(Fixture& f, const char* type, long long count) {
  Json cfg{{"type", type}};
  if (count > 0) cfg["count"] = count;
  Params sp(cfg, "render.sampler");
  sp.string("type");
  return samplers().get(type, "type")(sp, f.scene)->generate(f.scene, f.density);
}
std::vector<RadianceSample> jittered(Fixture& f, long long count) {
  return samplesOf(f, "jittered", count);
}

/// Evaluation (S and ∇S by volume tracing) + Eq. 4 gather into the 128^3 volume: what
/// replaces the per-voxel tracing. Sample positions are generated outside the loop (the
/// sampler is a stage of its own, timed by BM_InterpJitteredSampler).
/// Evaluation + Eq. 4 gather of `s` into a 128³ volume, timed per iteration.
void gradientVolume(benchmark::State& state, Fixture& f, std::vector<RadianceSample> s) {
  const TracerSteps steps{f.scene.medium.voxelSize(), f.scene.medium.voxelSize()};
  RadianceGrid out(f.scene.medium.bounds, IVec3(128));
  long long uncovered = 0;
  for (auto _ : state) {
    evaluateSamples(f.scene, f.density, steps, s, true);
    uncovered = interpolateSamples(Interpolation::Gradient, f.density, s, out).uncovered;
    benchmark::DoNotOptimize(out.data().data());
  }
  state.counters["samples"] = double(s.size());
  state.counters["uncovered"] = double(uncovered);
}

void BM_InterpGradient128(benchmark::State& state) {
  Fixture& f = Fixture::get();
  gradientVolume(state, f, jittered(f, state.range(0)));
}
BENCHMARK(BM_InterpGradient128)
    ->Arg(512)
    ->Arg(2048)
    ->Arg(8192)
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime()
    ->MeasureProcessCPUTime();

/// The same with grid samples: valid radius h instead of 1.75·h, so ~4 instead of ~22
/// samples cover each voxel (the gather's cost is proportional to that overlap).
void BM_InterpGradientGrid128(benchmark::State& state) {
  Fixture& f = Fixture::get();
  gradientVolume(state, f, samplesOf(f, "grid", state.range(0)));
}
BENCHMARK(BM_InterpGradientGrid128)
    ->Arg(512)
    ->Arg(2048)
    ->Arg(8192)
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime()
    ->MeasureProcessCPUTime();

/// The same with the Gaussian centres of the scene (800 samples, R = 3r).
void BM_InterpGradientGaussianCentres128(benchmark::State& state) {
  Fixture& f = Fixture::get();
  gradientVolume(state, f, samplesOf(f, "gaussian-centres", 0));
}
BENCHMARK(BM_InterpGradientGaussianCentres128)->Unit(benchmark::kMillisecond)->UseRealTime();

void BM_InterpJitteredSampler(benchmark::State& state) {
  Fixture& f = Fixture::get();
  for (auto _ : state) benchmark::DoNotOptimize(jittered(f, state.range(0)).data());
}
BENCHMARK(BM_InterpJitteredSampler)
    ->Arg(512)
    ->Arg(8192)
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();

/// The reconstruction alone (samples evaluated once, outside the loop).
void BM_InterpGatherOnly128(benchmark::State& state) {
  Fixture& f = Fixture::get();
  const Json cfg{{"type", "jittered"}, {"count", state.range(0)}};
  Params sp(cfg, "render.sampler");
  sp.string("type");
  std::vector<RadianceSample> s =
      samplers().get("jittered", "type")(sp, f.scene)->generate(f.scene, f.density);
  evaluateSamples(f.scene, f.density, {f.scene.medium.voxelSize(), f.scene.medium.voxelSize()}, s,
                  true);
  RadianceGrid out(f.scene.medium.bounds, IVec3(128));
  for (auto _ : state) {
    interpolateSamples(Interpolation::Gradient, f.density, s, out);
    benchmark::DoNotOptimize(out.data().data());
  }
  state.counters["samples"] = double(s.size());
}
BENCHMARK(BM_InterpGatherOnly128)
    ->Arg(512)
    ->Arg(2048)
    ->Arg(8192)
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime()
    ->MeasureProcessCPUTime();

/// Issue 14: the reconstruction's cost against the spheres and the volume. 512 samples on an
/// 8×8×8 lattice of spacing R voxels, each of radius R = range(1) voxels, in a range(0)³
/// unit-box volume whose density is non-zero in the lattice's box only (one voxel inside it),
/// so every occupied voxel is covered (the nearest-sample rule, whose cost grows with the
/// uncovered occupied voxels, is not exercised). The spheres cover 512·(4/3)π·R³ voxels at
/// every size: what grows from 64³ to 256³ at equal R is the part proportional to the volume
/// (writing the output, the one pass over the density rows).
void BM_InterpGatherScaling(benchmark::State& state) {
  const int res = int(state.range(0));
  const int R = int(state.range(1));
  const Box unit{Vec3(0.0f), Vec3(1.0f)};
  const float h = 1.0f / float(res);
  const int lo = (res - 7 * R) / 2;  // first lattice point's voxel
  DensityGrid d(unit, IVec3(res), 0.0f);
  for (int k = lo + 1; k < lo + 7 * R; ++k)
    for (int j = lo + 1; j < lo + 7 * R; ++j)
      for (int i = lo + 1; i < lo + 7 * R; ++i) d.at(i, j, k) = 1.0f;
  std::vector<RadianceSample> s;
  for (int c = 0; c < 512; ++c) {
    RadianceSample x;
    x.position =
        (Vec3(float(lo + R * (c % 8)), float(lo + R * (c / 8 % 8)), float(lo + R * (c / 64))) +
         0.5f) *
        h;
    x.radius = float(R) * h;
    x.S = Vec3(1.0f + 0.01f * float(c % 7));
    x.dS[0] = x.dS[1] = x.dS[2] = Vec3(0.1f);
    s.push_back(x);
  }
  RadianceGrid out(unit, IVec3(res));
  long long uncovered = 0;
  for (auto _ : state) {
    uncovered = interpolateSamples(Interpolation::Gradient, d, s, out).uncovered;
    benchmark::DoNotOptimize(out.data().data());
  }
  state.counters["uncovered"] = double(uncovered);
  state.counters["sphere_voxels"] = 512.0 * 4.18879 * R * R * R;
  state.counters["volume_voxels"] = double(res) * res * res;
}
BENCHMARK(BM_InterpGatherScaling)
    ->ArgsProduct({{64, 128, 256}, {2, 4, 8}})
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime()
    ->MeasureProcessCPUTime();

}  // namespace
}  // namespace scatterlab
