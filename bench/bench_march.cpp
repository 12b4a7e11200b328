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
///   ManyLamps/<far_field>/<moved>: a Renderer's frames of fig3 with 64 lamps on a ring
///     (bench::addLampRing), `gradient` at its defaults, 800×600, with render.far_field 0 or 16;
///     moved 0 = the camera (the far field kept), 1 = one lamp (the far field updated for it),
///     2 = a new Renderer per frame (cold: the density, samples and far field built anew).
///     Counters march_ms (the march stage of the last frame) and far_terms (its
///     far_field_terms).
/// The CPU column is the process's CPU time (all threads): on a shared, oversubscribed machine
/// it measures the work better than the wall time does.

#include <benchmark/benchmark.h>

#include <map>
#include <memory>

#include "api/scatterlab.h"
#include "bench/bench_scenes.h"
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

void BM_ManyLamps(benchmark::State& state) {
  initialize();
  const int far = int(state.range(0)), moved = int(state.range(1));
  Json doc = readJsonFile(SCATTERLAB_SOURCE_DIR "/data/scenes/fig3.json");
  doc["camera"]["width"] = 800;
  doc["camera"]["height"] = 600;
  doc["render"]["method"] = "gradient";
  doc["render"]["far_field"] = far;
  bench::addLampRing(doc, 64);
  const auto make = [&] {
    return std::make_unique<Renderer>(doc, SCATTERLAB_SOURCE_DIR "/data/scenes", "gradient", "cpu");
  };
  std::unique_ptr<Renderer> r = make();
  r->render();
  const Json p0 = doc["lights"][0]["position"], c0 = doc["camera"]["position"];
  double march = 0, terms = 0;
  int frame = 0;
  for (auto _ : state) {
    ++frame;
    if (moved == 2) {
      state.PauseTiming();
      r.reset();
      state.ResumeTiming();
      r = make();
    } else if (moved == 1) {
      r->set("lights.0.position=[" + std::to_string(p0[0].get<double>() + 0.002 * (frame % 5)) +
             "," + p0[1].dump() + "," + p0[2].dump() + "]");
    } else {
      r->set("camera.position=[" + std::to_string(c0[0].get<double>() + 0.01 * (frame % 5)) + "," +
             c0[1].dump() + "," + c0[2].dump() + "]");
    }
    const RenderResult res = r->render();
    for (const auto& [stage, ms] : res.stats.timingsMs)
      if (stage == "march") march = ms;
    terms = res.stats.extra.value("far_field_terms", 0.0);
  }
  state.counters["march_ms"] = march;
  state.counters["far_terms"] = terms;
}

BENCHMARK(BM_ManyLamps)
    ->ArgsProduct({{0, 16}, {0, 1, 2}})
    ->Unit(benchmark::kMillisecond)
    ->MeasureProcessCPUTime()
    ->UseRealTime()
    ->Iterations(3);
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
