/// Scene objects (issue 12) on the CPU: `exact` at 320x240 on data/scenes/bunny_spot.json
/// (128³, the 3,851-triangle Stanford bunny and a floor, one spot light) with and without its
/// objects; loading the scene (OBJ parse + Embree BVH build); Embree shadow-ray throughput.

#include <benchmark/benchmark.h>

#include <random>

#include "api/scatterlab.h"

using namespace scatterlab;

namespace {

const std::string kBunny = std::string(SCATTERLAB_SOURCE_DIR) + "/data/scenes/bunny_spot.json";

bool loadBunny(benchmark::State& state, Scene& scene, std::vector<std::string> set = {}) {
  initialize();
  try {
    scene = loadScene(kBunny, std::move(set));
  } catch (const IoError& e) {
    state.SkipWithError(e.what());
    return false;
  }
  return true;
}

/// Arg 1: with the scene's objects; 0: `objects=[]`.
void BM_Exact_BunnySpot_320x240(benchmark::State& state) {
  Scene scene;
  std::vector<std::string> set;
  if (state.range(0) == 0) set.push_back("objects=[]");
  if (!loadBunny(state, scene, set)) return;
  auto m = createMethod(scene, "exact", "cpu");
  for (auto _ : state) benchmark::DoNotOptimize(m->render(scene, nullptr));
}

void BM_LoadScene_BunnySpot(benchmark::State& state) {
  Scene scene;
  for (auto _ : state)
    if (!loadBunny(state, scene)) return;
}

/// Shadow rays from random points of the medium box to the spot light, one thread.
void BM_OcclusionRays_BunnySpot(benchmark::State& state) {
  Scene scene;
  if (!loadBunny(state, scene)) return;
  std::mt19937 rng(1);
  std::uniform_real_distribution<float> u(0.0f, 1.0f);
  std::vector<Vec3> points(4096);
  for (Vec3& p : points) p = Vec3(u(rng), u(rng), u(rng));
  const Vec3 light = scene.lights[0].position;
  long long blocked = 0, n = 0;
  for (auto _ : state)
    for (const Vec3& p : points) {
      const Vec3 d = light - p;
      const float len = glm::length(d);
      blocked += scene.objects->occluded(p, d / len, 0.0f, len);
      ++n;
    }
  state.counters["rays_per_s"] = benchmark::Counter(double(n), benchmark::Counter::kIsRate);
  state.counters["blocked_share"] = double(blocked) / double(std::max(n, 1LL));
}

}  // namespace

BENCHMARK(BM_Exact_BunnySpot_320x240)->Arg(1)->Arg(0)->Unit(benchmark::kMillisecond)->UseRealTime();
BENCHMARK(BM_LoadScene_BunnySpot)->Unit(benchmark::kMillisecond)->UseRealTime();
BENCHMARK(BM_OcclusionRays_BunnySpot)->Unit(benchmark::kMillisecond)->UseRealTime();
