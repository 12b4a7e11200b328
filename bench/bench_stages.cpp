/// Registry-driven stage micro-benchmarks (issue 7): one benchmark per registered name and
/// volume size, generated at start-up by iterating the registries (benchmark::RegisterBenchmark),
/// so a newly registered variant is benchmarked without editing this file:
///   Stage/sampler/<name>/<res>, Stage/evaluator/<name>/<backend>/<res>,
///   Stage/reconstruction/<name>/<backend>/<res>, Stage/integrator/<name>/<backend>/<res>,
///   Stage/method/<name>/<res>
/// Scene: data/scenes/glow.json (five Gaussian blobs, one point light) at res³ voxels and a
/// 400×300 image; 512 samples from the `jittered` sampler feed the evaluators and
/// reconstructions. Each stage runs in a frame of its backend (the density built there, the
/// integrators' radiance volume by that backend's "gradient"). GPU variants are timed with GL
/// timer queries around the call and reported as manual time (so the CPU-side readback of
/// samples is excluded); they are skipped with a reason when there is no EGL context.
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

/// A frame of backend `b` with the scene's density built in it.
std::unique_ptr<Frame> frameWithDensity(Backend b, const Scene& scene) {
  std::unique_ptr<Frame> f = backends()[int(b)].makeFrame(PipelineSettings{});
  f->buildDensity(scene);
  return f;
}

/// Settings as the method layer would parse them from an empty render object.
PipelineSettings defaultSettings(const Scene& scene) {
  PipelineSettings s;
  s.march.step = s.delta1 = s.delta2 = scene.medium.voxelSize();
  s.radianceResolution = scene.medium.resolution;
  return s;
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
};

const Inputs& inputs(int res) {
  static std::map<int, Inputs> cache;
  auto it = cache.find(res);
  if (it != cache.end()) return it->second;
  Inputs in;
  in.scene = stageScene(res);
  in.density = buildDensityVolume(in.scene);
  Json sp = {{"count", 512}};
  Params p(sp, "sampler");
  in.samples = samplers().get("jittered", "sampler")(p, in.scene)->generate(in.scene, in.density);
  const PipelineSettings ps = defaultSettings(in.scene);
  HostFrame frame(in.density);
  radianceEvaluators()
      .get("volume-tracer", "")
      .on[int(Backend::Cpu)](ps)
      ->evaluate(frame, in.scene, in.samples, true);
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
      registerOne("Stage/sampler/" + name + "/" + std::to_string(res), false, 5,
                  [name, res](benchmark::State& state) {
                    const Inputs& in = inputs(res);
                    Json j = {{"count", 512}};
                    Params p(j, "sampler");
                    try {
                      auto s = samplers().get(name, "sampler")(p, in.scene);
                      long long n = 0;
                      timeLoop(state, false,
                               [&] { n = (long long)s->generate(in.scene, in.density).size(); });
                      state.counters["samples"] = double(n);
                    } catch (const std::exception& e) {
                      state.SkipWithError(e.what());
                    }
                  });
  for (const Backend b : {Backend::Cpu, Backend::Gpu}) {
    if (!backends()[int(b)].makeFrame) continue;
    const bool gpu = b == Backend::Gpu;
    const std::string on = std::string("/") + backendName(b) + "/";
    for (const std::string& name : radianceEvaluators().names()) {
      if (!radianceEvaluators().get(name, "").has(b)) continue;
      for (int res : kSizes)
        registerOne(
            "Stage/evaluator/" + name + on + std::to_string(res), gpu, 3,
            [name, res, b, gpu](benchmark::State& state) {
              const Inputs& in = inputs(res);
              try {
                auto frame = frameWithDensity(b, in.scene);
                auto ev = radianceEvaluators().get(name, "").on[int(b)](defaultSettings(in.scene));
                std::vector<RadianceSample> s = in.samples;
                timeLoop(state, gpu, [&] { ev->evaluate(*frame, in.scene, s, true); });
                state.counters["samples"] = double(s.size());
              } catch (const std::exception& e) {
                state.SkipWithError(e.what());
              }
            });
    }
    for (const std::string& name : reconstructions().names()) {
      if (!reconstructions().get(name, "").has(b)) continue;
      for (int res : kSizes)
        registerOne("Stage/reconstruction/" + name + on + std::to_string(res), gpu,
                    name == "per-voxel" ? 1 : 3, [name, res, b, gpu](benchmark::State& state) {
                      const Inputs& in = inputs(res);
                      try {
                        auto frame = frameWithDensity(b, in.scene);
                        auto rc =
                            reconstructions().get(name, "").on[int(b)](defaultSettings(in.scene));
                        timeLoop(state, gpu, [&] {
                          rc->reconstruct(*frame, in.scene, in.samples, in.scene.medium.resolution,
                                          nullptr);
                        });
                      } catch (const std::exception& e) {
                        state.SkipWithError(e.what());
                      }
                    });
    }
    for (const std::string& name : integrators().names()) {
      if (!integrators().get(name, "").has(b)) continue;
      for (int res : kSizes)
        registerOne("Stage/integrator/" + name + on + std::to_string(res), gpu, 2,
                    [name, res, b, gpu](benchmark::State& state) {
                      const Inputs& in = inputs(res);
                      try {
                        const PipelineSettings ps = defaultSettings(in.scene);
                        auto frame = frameWithDensity(b, in.scene);
                        reconstructions()
                            .get("gradient", "")
                            .on[int(b)](ps)
                            ->reconstruct(*frame, in.scene, in.samples, in.scene.medium.resolution,
                                          nullptr);
                        auto ig = integrators().get(name, "").on[int(b)](ps);
                        timeLoop(state, gpu, [&] {
                          Image img = ig->integrate(*frame, in.scene, nullptr);
                          benchmark::DoNotOptimize(img.pixels().data());
                        });
                      } catch (const std::exception& e) {
                        state.SkipWithError(e.what());
                      }
                    });
    }
  }
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
