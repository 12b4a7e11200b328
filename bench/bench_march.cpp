/// The CPU march (issue 14): the integrator stage in one binary so a run gives the ratios at one
/// load:
///   March/<scene>/<mode>: ray-marcher through a 128³ density + radiance volume, 800×600;
///     mode 0 = the plain march (render.fast_march false), 1 = fast march with the sse2 kernel
///     (the previous session's fast march, moved into cpu/fused_march_sse2.cpp), 2 = the avx2
///     kernel (render.march_simd avx2), 3 = avx2 with render.half_float_volumes, 4 and 5 = avx2
///     with render.march_scale 2 and 4 (depth-aware upsampling; not the same image), 6 and 7 =
///     plain and avx2 with factored lights (the default of gradient and adaptive: S = V·A with
///     A evaluated per step; the volume's values are not V here, which does not change the work);
///   Exact/<scene>/<fast>: fast march off (0) or on (1);
///   Exact/<scene>/<fast>: the exact integrator (shadow rays traced per step), 800×600.
/// Scenes: fig3 (the Fig. 3 plume: 800 Gaussians, about half the voxels empty), smoke1
/// (data/scenes/smoke1_sun.json: OpenVDB smoke1 resampled to 128³, sparse, directional light),
/// shaft (uniform medium: nothing to skip, the dense case). The radiance volume is the gradient
/// reconstruction of 512 jittered samples (its values do not change the march's work).
/// Exact/smoke1 marches smoke1 at its native 111×222×112 voxels with primary step 1 voxel and
/// shadow step 3 voxels (render.delta1), the settings of the vdb_render comparison in
/// docs/benchmarks.md. Run with --benchmark_enable_random_interleaving=true and repetitions.
/// The CPU column is the process's CPU time (all threads): on a shared, oversubscribed machine
/// it measures the work better than the wall time does.

#include <benchmark/benchmark.h>

#include <map>

#include "api/scatterlab.h"
#include "core/method.h"
#include "core/stages.h"
#include "cpu/fused_march.h"

namespace scatterlab {
namespace {

Scene marchScene(const std::string& name, bool native = false) {
  const std::string file = name == "smoke1" ? "smoke1_sun" : name;
  Scene s = loadScene(SCATTERLAB_SOURCE_DIR "/data/scenes/" + file + ".json");
  if (!native) s.medium.resolution = IVec3(128);
  s.camera.width = 800;
  s.camera.height = 600;
  return s;
}

PipelineSettings marchSettings(const Scene& scene, int mode) {
  PipelineSettings s;
  s.march.step = s.delta1 = s.delta2 = scene.medium.voxelSize();
  s.march.fast = mode != 0;
  RayMarcherSettings r;
  r.simd = mode == 1 ? MarchSimd::Sse2 : mode >= 2 ? MarchSimd::Avx2 : MarchSimd::Auto;
  r.halfFloat = mode == 3;
  s.march.scale = mode == 4 ? 2 : mode == 5 ? 4 : 1;
  if (mode >= 6) {
    s.march.fast = mode == 7;
    r.simd = MarchSimd::Avx2;
    s.factorLights = true;
  }
  s.integratorKeys.set(r);
  s.radianceResolution = scene.medium.resolution;
  return s;
}

/// Scene and a CPU frame with its density and a radiance volume, per scene name.
struct MarchInputs {
  Scene scene;
  std::unique_ptr<Frame> frame;
};

MarchInputs& marchInputs(const std::string& name) {
  static std::map<std::string, MarchInputs> cache;
  auto it = cache.find(name);
  if (it != cache.end()) return it->second;
  initialize();
  MarchInputs in;
  in.scene = marchScene(name);
  in.frame = backends()[int(Backend::Cpu)].makeFrame(PipelineSettings{});
  in.frame->buildDensity(in.scene);
  Json sp = {{"count", 512}};
  Params p(sp, "sampler");
  const PipelineSettings ps = marchSettings(in.scene, 1);
  std::vector<RadianceSample> samples = samplers()
                                            .get("jittered", "sampler")(p, in.scene)
                                            ->generate(in.scene, in.frame->hostDensity());
  radianceEvaluators()
      .get("volume-tracer", "")
      .on[int(Backend::Cpu)](ps)
      ->evaluate(*in.frame, in.scene, samples, true);
  reconstructions()
      .get("gradient", "")
      .on[int(Backend::Cpu)](ps)
      ->reconstruct(*in.frame, in.scene, samples, in.scene.medium.resolution, nullptr);
  return cache.emplace(name, std::move(in)).first->second;
}

void BM_March(benchmark::State& state, const std::string& name) {
  if (state.range(0) >= 2 && state.range(0) != 6 && !cpuHasAvx2Kernel()) {
    state.SkipWithError("this CPU has no AVX2 + FMA + F16C");
    return;
  }
  MarchInputs& in = marchInputs(name);
  auto ig = integrators()
                .get("ray-marcher", "")
                .on[int(Backend::Cpu)](marchSettings(in.scene, int(state.range(0))));
  for (auto _ : state) {
    Image img = ig->integrate(*in.frame, in.scene, nullptr);
    benchmark::DoNotOptimize(img.pixels().data());
  }
}

void BM_Exact(benchmark::State& state, const std::string& name) {
  static std::map<std::string, MarchInputs> cache;
  MarchInputs& in = cache[name];
  if (!in.frame) {
    initialize();
    in.scene = marchScene(name, true);
    in.frame = backends()[int(Backend::Cpu)].makeFrame(PipelineSettings{});
    in.frame->buildDensity(in.scene);
  }
  PipelineSettings ps = marchSettings(in.scene, int(state.range(0)));
  ps.delta1 = 3.0f * in.scene.medium.voxelSize();
  auto ig = integrators().get("exact", "").on[int(Backend::Cpu)](ps);
  for (auto _ : state) {
    Image img = ig->integrate(*in.frame, in.scene, nullptr);
    benchmark::DoNotOptimize(img.pixels().data());
  }
}

BENCHMARK_CAPTURE(BM_March, fig3, std::string("fig3"))
    ->DenseRange(0, 7)
    ->Unit(benchmark::kMillisecond)
    ->MeasureProcessCPUTime()
    ->UseRealTime()
    ->Iterations(2);
BENCHMARK_CAPTURE(BM_March, smoke1, std::string("smoke1"))
    ->DenseRange(0, 7)
    ->Unit(benchmark::kMillisecond)
    ->MeasureProcessCPUTime()
    ->UseRealTime()
    ->Iterations(2);
BENCHMARK_CAPTURE(BM_March, shaft, std::string("shaft"))
    ->DenseRange(0, 7)
    ->Unit(benchmark::kMillisecond)
    ->MeasureProcessCPUTime()
    ->UseRealTime()
    ->Iterations(2);
BENCHMARK_CAPTURE(BM_Exact, smoke1, std::string("smoke1"))
    ->Arg(0)
    ->Arg(1)
    ->Unit(benchmark::kMillisecond)
    ->MeasureProcessCPUTime()
    ->UseRealTime()
    ->Iterations(1);

}  // namespace
}  // namespace scatterlab
