/// A 48-frame animation (issue 15): data/scenes/glow_orbit.json, the glow's lamp circling the
/// smoke along its keyframed path, frame f at time f/24, rendered
///   Animation/renderer/<method>/<backend>: through one scatterlab::Renderer (density volume,
///     method and GL context kept; api/renderer.h), and
///   Animation/separate/<method>/<backend>: as 48 separate renders, each loading the scene,
///     creating the method and rendering (what 48 `scatterlab render` calls do, less process
///     start-up).
/// One iteration = 48 frames; the counter ms_per_frame is the wall time per frame. The ratio of
/// the two is in docs/benchmarks.md ("Animation"). GPU variants are skipped without an EGL context.
///   BM_RendererSet/<case>: what an engine's per-frame update costs the host (issue 33:
///     microseconds, not a copy of the scene): Renderer::set of light 0's position (as a string,
///     0; typed, setLight, 1), of the camera's position (2), and of every light's position in one
///     setAll (3), on fig3 (800 Gaussian blobs) with one light or 64 (arg 1); no render in the
///     loop. CPU backend: set() does no GL work unless a key of the render block or the medium
///     changes.

#include <benchmark/benchmark.h>

#include <chrono>
#include <string>
#include <vector>

#include "api/scatterlab.h"
#include "bench_scenes.h"
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

void BM_RendererSet(benchmark::State& state) {
  initialize();
  Json doc = readJsonFile(SCATTERLAB_SOURCE_DIR "/data/scenes/fig3.json");
  bench::addLampRing(doc, int(state.range(1)));
  Renderer r(doc, SCATTERLAB_SOURCE_DIR "/data/scenes", "gradient", "cpu");
  const Json p0 = doc["lights"][0]["position"], c0 = doc["camera"]["position"];
  Light light = r.scene().lights[0];
  Camera camera = r.scene().camera;
  std::vector<std::string> all(r.scene().lights.size());
  int frame = 0;
  for (auto _ : state) {
    const double dx = 0.002 * (++frame % 5);
    switch (state.range(0)) {
      case 0:
        r.set("lights.0.position=[" + std::to_string(p0[0].get<double>() + dx) + "," +
              p0[1].dump() + "," + p0[2].dump() + "]");
        break;
      case 1:
        light.position.x = float(p0[0].get<double>() + dx);
        r.setLight(0, light);
        break;
      case 2:
        camera.position.x = float(c0[0].get<double>() + dx);
        r.setCamera(camera);
        break;
      default:
        for (std::size_t l = 0; l < all.size(); ++l) {
          const Json& p = doc["lights"][l]["position"];
          all[l] = "lights." + std::to_string(l) + ".position=[" +
                   std::to_string(p[0].get<double>() + dx) + "," + p[1].dump() + "," + p[2].dump() +
                   "]";
        }
        r.setAll(all);
    }
  }
  const char* const what[] = {"set(\"lights.0.position=...\")", "setLight", "setCamera",
                              "setAll of every light's position"};
  state.SetLabel(std::string(what[state.range(0)]) + ", fig3, " + std::to_string(state.range(1)) +
                 " light(s)");
}

BENCHMARK(BM_RendererSet)->ArgsProduct({{0, 1, 2, 3}, {1, 64}})->Unit(benchmark::kMicrosecond);

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
