/// A 48-frame animation (issue 15): data/scenes/glow_orbit.json, the glow's lamp circling the
/// smoke along its keyframed path, frame f at time f/24, rendered
///   Animation/renderer/<method>/<backend>: through one scatterlab::Renderer (density volume,
///     method and GL context kept; api/renderer.h), and
///   Animation/separate/<method>/<backend>: as 48 separate renders, each loading the scene,
///     creating the method and rendering (what 48 `scatterlab render` calls do, less process
///     start-up).
/// One iteration = 48 frames; the counter ms_per_frame is the wall time per frame. The ratio of
/// the two is in docs/benchmarks.md ("Animation"). GPU variants are skipped without an EGL context.

#include <benchmark/benchmark.h>

#include <chrono>
#include <string>

#include "api/scatterlab.h"
#include "gpu/context.h"

namespace scatterlab {
namespace {

constexpr int kFrames = 48;
constexpr double kFps = 24.0;
const char* const kScene = SCATTERLAB_SOURCE_DIR "/data/scenes/glow_orbit.json";

bool skipWithoutGpu(benchmark::State& state, const std::string& backend) {
  std::string why;
  if (backend == "gpu" && !gpu::tryContext(&why)) {
    state.SkipWithError(("no GPU context: " + why).c_str());
    return true;
  }
  return false;
}

void animationRenderer(benchmark::State& state, std::string method, std::string backend) {
  initialize();
  if (skipWithoutGpu(state, backend)) return;
  double checksum = 0.0;
  const auto start = std::chrono::steady_clock::now();
  for (auto _ : state) {
    Renderer r = Renderer::fromFile(kScene, {}, method, backend);
    for (int f = 0; f < kFrames; ++f) {
      r.setTime(f / kFps);
      checksum += r.render().image.at(160, 120).x;
    }
  }
  benchmark::DoNotOptimize(checksum);
  const double ms =
      std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
  state.counters["ms_per_frame"] = ms / (double(state.iterations()) * kFrames);
}

void animationSeparate(benchmark::State& state, std::string method, std::string backend) {
  initialize();
  if (skipWithoutGpu(state, backend)) return;
  double checksum = 0.0;
  const auto start = std::chrono::steady_clock::now();
  for (auto _ : state) {
    for (int f = 0; f < kFrames; ++f) {
      // Frame f's scene as `render --set` would give it: the document read at time f/24.
      Json doc = readJsonFile(kScene);
      const Scene s = parseScene(sceneAtTime(doc, f / kFps), SCATTERLAB_SOURCE_DIR "/data/scenes");
      checksum += createMethod(s, method, backend)->render(s, nullptr).image.at(160, 120).x;
    }
  }
  benchmark::DoNotOptimize(checksum);
  const double ms =
      std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
  state.counters["ms_per_frame"] = ms / (double(state.iterations()) * kFrames);
}

void registerAll() {
  for (const char* method : {"gradient", "per-voxel"})
    for (const char* backend : {"cpu", "gpu"}) {
      const std::string tail = std::string(method) + "/" + backend;
      benchmark::RegisterBenchmark(("Animation/renderer/" + tail).c_str(), animationRenderer,
                                   method, backend)
          ->Iterations(1)
          ->Unit(benchmark::kMillisecond)
          ->UseRealTime();
      benchmark::RegisterBenchmark(("Animation/separate/" + tail).c_str(), animationSeparate,
                                   method, backend)
          ->Iterations(1)
          ->Unit(benchmark::kMillisecond)
          ->UseRealTime();
    }
}

const int registered = (registerAll(), 0);

}  // namespace
}  // namespace scatterlab
