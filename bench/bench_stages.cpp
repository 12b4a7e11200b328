/// Registry-driven stage micro-benchmarks (issue 7): one benchmark per registered name and
/// volume size, generated at start-up by iterating the registries (benchmark::RegisterBenchmark),
/// so a newly registered variant is benchmarked without editing this file:
///   Stage/sampler/<name>/<res>, Stage/evaluator/<name>/<res>, Stage/reconstruction/<name>/<res>,
///   Stage/integrator/<name>/<res>, Stage/method/<name>/<res>
/// Scene: data/scenes/glow.json (five Gaussian blobs, one point light) at res³ voxels and a
/// 400×300 image; 512 samples from the `jittered` sampler feed the evaluators and
/// reconstructions. GPU variants (names ending in "-gpu", and "slice-marcher") are timed with GL
/// timer queries around the call and reported as manual time (so the CPU-side readback to host
/// memory is excluded); they are skipped with a reason when there is no EGL context.
/// Iterations are kept small (SCATTERLAB_STAGE_BENCH_ITERS overrides) so the whole set finishes
/// on the 2-core machine; docs/harness.md shows the JSON output.
/// Density models are not here: each type needs its own parameters (bench_media.cpp has them).

#include <benchmark/benchmark.h>

#include <cstdlib>
#include <functional>
#include <string>

#include "api/scatterlab.h"
#include "core/method.h"
#include "core/stages.h"
#include "gpu/context.h"
#include "gpu/timer.h"
#include "render/methods.h"

namespace scatterlab {
namespace {

const int kSizes[] = {32, 64, 128};

Scene stageScene(int res) {
  Scene s = loadScene(SCATTERLAB_SOURCE_DIR "/data/scenes/glow.json");
  s.medium.resolution = IVec3(res);
  s.camera.width = 400;
  s.camera.height = 300;
  return s;
}

bool isGpuVariant(const std::string& name) {
  return (name.size() > 4 && name.compare(name.size() - 4, 4, "-gpu") == 0) ||
         name == "slice-marcher";
}

int iters(int n) {
  const char* e = std::getenv("SCATTERLAB_STAGE_BENCH_ITERS");
  return e && std::atoi(e) > 0 ? std::atoi(e) : n;
}

/// The shared inputs of one size: scene, density volume, evaluated samples, a radiance volume.
struct Inputs {
  Scene scene;
  DensityGrid density;
  std::vector<RadianceSample> samples;
  RadianceGrid radiance;
};

const Inputs& inputs(int res) {
  static std::map<int, Inputs> cache;
  auto it = cache.find(res);
  if (it != cache.end()) return it->second;
  Inputs in;
  in.scene = stageScene(res);
  RenderStats st;
  in.density = buildDensityVolume(in.scene, st);
  Json sp = {{"count", 512}};
  Params p(sp, "sampler");
  in.samples = samplers().get("jittered", "sampler")(p, in.scene)->generate(in.scene, in.density);
  Json ep = Json::object();
  Params pe(ep, "render");
  radianceEvaluators().get("volume-tracer", "evaluator")(pe, in.scene)
      ->evaluate(in.scene, in.density, in.samples, true);
  in.radiance = RadianceGrid(in.scene.medium.bounds, in.scene.medium.resolution);
  Params pr(ep, "render");
  reconstructions().get("gradient", "reconstruction")(pr, in.scene)
      ->reconstruct(in.scene, in.density, in.samples, in.radiance);
  return cache.emplace(res, std::move(in)).first->second;
}

/// Times `body` per iteration: wall time for CPU variants, GPU timestamps for GPU ones.
void timeLoop(benchmark::State& state, bool gpuVariant, const std::function<void()>& body) {
  if (gpuVariant) {
    std::string why;
    if (!gpu::tryContext(&why)) {
      state.SkipWithError(("no GPU context: " + why).c_str());
      return;
    }
    for (auto _ : state) {
      gpu::StageTimer t;
      t.begin("stage");
      body();
      t.end();
      double ms = 0;
      for (const auto& [s, v] : t.results()) ms += v;
      state.SetIterationTime(ms * 1e-3);
    }
    state.SetLabel(gpu::context().info().renderer);
  } else {
    for (auto _ : state) body();
  }
}

template <class Make>
void registerOne(const std::string& name, bool gpuVariant, int n, Make&& fn) {
  auto* b = benchmark::RegisterBenchmark(name.c_str(), std::forward<Make>(fn));
  b->Unit(benchmark::kMillisecond)->Iterations(iters(n));
  if (gpuVariant) b->UseManualTime();
}

bool registerAll() {
  initialize();
  for (const std::string& name : samplers().names())
    for (int res : kSizes)
      registerOne("Stage/sampler/" + name + "/" + std::to_string(res), isGpuVariant(name), 5,
                  [name, res](benchmark::State& state) {
                    const Inputs& in = inputs(res);
                    Json j = {{"count", 512}};
                    Params p(j, "sampler");
                    try {
                      auto s = samplers().get(name, "sampler")(p, in.scene);
                      long long n = 0;
                      timeLoop(state, isGpuVariant(name), [&] {
                        n = (long long)s->generate(in.scene, in.density).size();
                      });
                      state.counters["samples"] = double(n);
                    } catch (const std::exception& e) {
                      state.SkipWithError(e.what());
                    }
                  });
  for (const std::string& name : radianceEvaluators().names())
    for (int res : kSizes)
      registerOne("Stage/evaluator/" + name + "/" + std::to_string(res), isGpuVariant(name), 3,
                  [name, res](benchmark::State& state) {
                    const Inputs& in = inputs(res);
                    Json j = Json::object();
                    Params p(j, "render");
                    try {
                      auto ev = radianceEvaluators().get(name, "evaluator")(p, in.scene);
                      std::vector<RadianceSample> s = in.samples;
                      timeLoop(state, isGpuVariant(name),
                               [&] { ev->evaluate(in.scene, in.density, s, true); });
                      state.counters["samples"] = double(s.size());
                    } catch (const std::exception& e) {
                      state.SkipWithError(e.what());
                    }
                  });
  for (const std::string& name : reconstructions().names())
    for (int res : kSizes)
      registerOne("Stage/reconstruction/" + name + "/" + std::to_string(res), isGpuVariant(name),
                  name.rfind("per-voxel", 0) == 0 ? 1 : 3, [name, res](benchmark::State& state) {
                    const Inputs& in = inputs(res);
                    Json j = Json::object();
                    Params p(j, "render");
                    try {
                      auto rc = reconstructions().get(name, "reconstruction")(p, in.scene);
                      RadianceGrid out(in.scene.medium.bounds, in.scene.medium.resolution);
                      timeLoop(state, isGpuVariant(name),
                               [&] { rc->reconstruct(in.scene, in.density, in.samples, out); });
                    } catch (const std::exception& e) {
                      state.SkipWithError(e.what());
                    }
                  });
  for (const std::string& name : integrators().names())
    for (int res : kSizes)
      registerOne("Stage/integrator/" + name + "/" + std::to_string(res), isGpuVariant(name), 2,
                  [name, res](benchmark::State& state) {
                    const Inputs& in = inputs(res);
                    Json j = Json::object();
                    Params p(j, "render");
                    try {
                      auto ig = integrators().get(name, "integrator")(p, in.scene);
                      timeLoop(state, isGpuVariant(name), [&] {
                        Image img = ig->integrate(in.scene, in.density, in.radiance);
                        benchmark::DoNotOptimize(img.pixels().data());
                      });
                    } catch (const std::exception& e) {
                      state.SkipWithError(e.what());
                    }
                  });
  // Whole methods on the CPU (the GPU ones are in bench_gpu.cpp), at the two smaller sizes.
  for (const std::string& name : methods().names())
    for (int res : {32, 64})
      registerOne("Stage/method/" + name + "/" + std::to_string(res), false, 1,
                  [name, res](benchmark::State& state) {
                    const Inputs& in = inputs(res);
                    try {
                      auto m = createMethod(in.scene, name, "cpu");
                      timeLoop(state, false, [&] {
                        RenderResult r = m->render(in.scene, nullptr);
                        benchmark::DoNotOptimize(r.image.pixels().data());
                      });
                    } catch (const std::exception& e) {
                      state.SkipWithError(e.what());
                    }
                  });
  return true;
}

const bool registered = registerAll();

}  // namespace
}  // namespace scatterlab
