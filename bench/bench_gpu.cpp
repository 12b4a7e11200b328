/// GPU stage benchmarks (issue 6): per-stage GPU times from timer queries, reported as manual
/// time, on the glow scene (five Gaussian blobs, one point light) at 64³ and 128³ and an
/// 800×600 image. Needs an EGL context; each benchmark reports an error when there is none.
/// On llvmpipe run with few iterations (see docs/benchmarks.md).

#include <benchmark/benchmark.h>

#include <algorithm>
#include <cstdlib>
#include <map>
#include <random>

#include "api/scatterlab.h"
#include "experiment/experiment.h"
#include "gpu/context.h"
#include "gpu/dynamic_sampling.h"
#include "gpu/reconstructions.h"
#include "gpu/slice_marcher.h"
#include "gpu/timer.h"
#include "gpu/tracing.h"
#include "gpu/view_march.h"
#include "gpu/volume.h"
#include "gpu/volume_tracer.h"
#include "media/procedural.h"
#include "media/sog.h"
#include "media/sog_fit.h"
#include "media/vdb.h"

namespace scatterlab {
namespace {

Scene glowScene(int res) {
  initialize();
  Scene s = loadScene(SCATTERLAB_SOURCE_DIR "/data/scenes/glow.json");
  s.medium.resolution = IVec3(res);
  s.camera.width = 800;
  s.camera.height = 600;
  return s;
}

bool needGpu(benchmark::State& state) {
  std::string why;
  if (gpu::tryContext(&why)) return true;
  state.SkipWithError(why.c_str());
  return false;
}

/// Runs `body` per iteration and reports the sum of the timer's GPU milliseconds.
template <class Body>
void gpuLoop(benchmark::State& state, Body&& body) {
  for (auto _ : state) {
    gpu::StageTimer timer;
    body(timer);
    double ms = 0;
    for (const auto& [stage, t] : timer.results()) ms += t;
    state.SetIterationTime(ms * 1e-3);
  }
  state.SetLabel(gpu::context().info().renderer);
}

std::vector<RadianceSample> samples512(const Scene& s) {
  std::mt19937 rng(1);
  std::uniform_real_distribution<float> u(0.1f, 0.9f);
  std::vector<RadianceSample> out(512);
  for (RadianceSample& r : out) {
    r.position = Vec3(u(rng), u(rng), u(rng));
    r.radius = 0.15f;
  }
  return out;
}

/// Arg 1 of the benchmarks with both pipelines: 0 compute (render.gpu_pipeline's default), 1
/// the paper's rasterised passes.
GpuPipeline pipelineArg(const benchmark::State& state) {
  return state.range(1) ? GpuPipeline::Raster : GpuPipeline::Compute;
}
const char* pipelineName(const benchmark::State& state) {
  return state.range(1) ? "raster" : "compute";
}

void BM_GpuDensitySplat(benchmark::State& state) {
  if (!needGpu(state)) return;
  const Scene s = glowScene(int(state.range(0)));
  const auto& g = dynamic_cast<const GaussianDensity&>(*s.medium.density);
  gpuLoop(state, [&](gpu::StageTimer& t) {
    gpu::Volume v = gpu::splatGaussians(g.blobs(), s.medium.bounds, s.medium.resolution, &t,
                                        pipelineArg(state));
    benchmark::DoNotOptimize(v.texture.id());
  });
  state.SetLabel(std::string(pipelineName(state)) + ", " + gpu::context().info().renderer);
}

void BM_GpuVolumeTracer512(benchmark::State& state) {
  if (!needGpu(state)) return;
  const Scene s = glowScene(int(state.range(0)));
  const gpu::Volume d = gpu::buildDensity(s);
  auto samples = samples512(s);
  const float vox = s.medium.voxelSize();
  gpuLoop(state, [&](gpu::StageTimer& t) {
    gpu::VolumeTracerGpu({vox, vox}).evaluate(s, d, samples, true, &t);
  });
}

void BM_GpuGradientSplat512(benchmark::State& state) {
  if (!needGpu(state)) return;
  const Scene s = glowScene(int(state.range(0)));
  const gpu::Volume d = gpu::buildDensity(s);
  auto samples = samples512(s);
  const float vox = s.medium.voxelSize();
  gpu::VolumeTracerGpu({vox, vox}).evaluate(s, d, samples, true, nullptr);
  gpuLoop(state, [&](gpu::StageTimer& t) {
    gpu::Volume v = gpu::GradientSplatGpu(false, false, std::nullopt, pipelineArg(state))
                        .reconstruct(d, samples, s.medium.bounds, s.medium.resolution, nullptr, &t);
    benchmark::DoNotOptimize(v.texture.id());
  });
  state.SetLabel(std::string(pipelineName(state)) + ", " + gpu::context().info().renderer);
}

void BM_GpuPerVoxel(benchmark::State& state) {
  if (!needGpu(state)) return;
  const Scene s = glowScene(int(state.range(0)));
  const gpu::Volume d = gpu::buildDensity(s);
  gpuLoop(state, [&](gpu::StageTimer& t) {
    gpu::Volume v = gpu::PerVoxelGpu(s.medium.voxelSize())
                        .build(s, d, s.medium.bounds, s.medium.resolution, nullptr, &t);
    benchmark::DoNotOptimize(v.texture.id());
  });
}

void BM_GpuSliceMarch800x600(benchmark::State& state) {
  if (!needGpu(state)) return;
  const Scene s = glowScene(int(state.range(0)));
  const gpu::Volume d = gpu::buildDensity(s);
  const gpu::Volume r = gpu::PerVoxelGpu(s.medium.voxelSize())
                            .build(s, d, s.medium.bounds, s.medium.resolution, nullptr, nullptr);
  MarchSettings ms;
  ms.step = s.medium.voxelSize();
  int slices = 0;
  gpuLoop(state, [&](gpu::StageTimer& t) {
    Image img = gpu::SliceMarcher(ms).integrate(s, d, r, &t, &slices);
    benchmark::DoNotOptimize(img.pixels().data());
  });
  state.counters["slices"] = slices;
}

/// The compute view march (render.gpu_pipeline = compute) on the same volumes and image as
/// BM_GpuSliceMarch800x600; the read-back is timed apart ("read-back" is not in the sum).
void BM_GpuViewMarch800x600(benchmark::State& state) {
  if (!needGpu(state)) return;
  const Scene s = glowScene(int(state.range(0)));
  const gpu::Volume d = gpu::buildDensity(s);
  const gpu::Volume r = gpu::PerVoxelGpu(s.medium.voxelSize())
                            .build(s, d, s.medium.bounds, s.medium.resolution, nullptr, nullptr);
  MarchSettings ms;
  ms.step = s.medium.voxelSize();
  gpu::ViewMarchGpu march(ms, false, ms.step, ShadowMapSettings{});
  gpuLoop(state, [&](gpu::StageTimer& t) {
    gpu::Texture kept;  // the image stays on the GPU: no read-back in the sum
    march.integrate(s, d, r, &t, &kept);
    benchmark::DoNotOptimize(kept.id());
  });
}

/// Wall time of one scatterlab::Renderer frame of `gradient` with the paper's 512 samples
/// (render.paper, the glow scene, 800×600), the light moved every frame so that every stage
/// but the density runs (sampling kept: the medium does not change), the image left on the GPU
/// (Renderer::keepImageOnDevice: no read-back); Arg 1 chooses the pipeline. What an engine
/// calling the library each frame waits for.
void BM_GpuRendererFrameGradient512(benchmark::State& state) {
  if (!needGpu(state)) return;
  initialize();
  Json doc = readJsonFile(SCATTERLAB_SOURCE_DIR "/data/scenes/glow.json");
  doc["medium"]["resolution"] = state.range(0);
  doc["camera"]["width"] = 800;
  doc["camera"]["height"] = 600;
  doc["render"] = {{"method", "gradient"},
                   {"paper", true},
                   {"sampler", {{"type", "jittered"}, {"count", 512}}},
                   {"gpu_pipeline", pipelineName(state)}};
  Renderer r(doc, SCATTERLAB_SOURCE_DIR "/data/scenes", "", "gpu");
  r.keepImageOnDevice(true);
  r.render();  // the density, the samples and the programs
  int frame = 0;
  for (auto _ : state) {
    r.set("lights.0.intensity=[" + std::to_string(1.0 + 0.01 * (++frame % 7)) + ",1,1]");
    const RenderResult res = r.render();
    benchmark::DoNotOptimize(res.deviceImage);
  }
  state.SetLabel(std::string(pipelineName(state)) + ", " + gpu::context().info().renderer);
}

/// The frames of the GPU report (issue 33, scripts/gpu-report.sh): what a user measures.
/// Arg 0 picks the case, arg 1 the resolution, arg 2 the light count, arg 3 the pipeline.
/// The paper's cases run the paper's configurations, as data/experiments/table2_gpu.json does
/// (so the harness's steady rows and these frames are the same work): the plume with the 512
/// Gaussians of largest mass, the shaft from a 541-point grid with ε = 1e-4 (2 748 samples at
/// 128³); the others the method's defaults. Until 2026-12-07 every case kept the scene's render
/// block: fig3's 800 Gaussian centres (every blob) for the paper's and the default `gradient`,
/// and the shaft's default grid (4 452 samples) — the H200 rows of 2026-11-27 are those.
struct FrameCase {
  const char* scene;        ///< data/scenes/NAME.json
  const char* method;       ///< render.method
  bool paper;               ///< render.paper
  int farField = 0;         ///< render.far_field (0: not set)
  const char* render = "";  ///< more render keys (a JSON object), or empty
};
constexpr FrameCase kFrameCases[] = {
    // the plume, the paper's samples: the 512 Gaussian centres of largest mass
    {"fig3", "gradient", true, 0, R"({"sampler": {"type": "gaussian-centres", "count": 512}})"},
    {"fig3", "gradient", false},  // the plume at the defaults
    {"fig3", "per-voxel", false},
    // the shaft, the paper's Fig. 4/5: a 541-point grid split at ε = 1e-4
    {"shaft", "adaptive", true, 0,
     R"({"sampler": {"type": "grid", "count": 541}, "epsilon": 1e-4})"},
    {"shaft", "adaptive", false},
    {"fig3", "gradient", false, 16},  // the defaults with A's far field (docs/gpu.md)
};

/// The case's scene at `res`³, 800×600, with `lights` lights: its first light on the harness's
/// ring (ringOfLights, experiment/experiment.h; before 2026-12-07 bench::addLampRing, another
/// ring), so that a frame here and the harness's steady row of data/experiments/table2_gpu.json
/// at the same light count are the same scene (scripts/gpu-targets.py compares them).
Json frameScene(const FrameCase& c, int res, int lights, bool raster) {
  Json doc = readJsonFile(std::string(SCATTERLAB_SOURCE_DIR "/data/scenes/") + c.scene + ".json");
  doc["medium"]["resolution"] = res;
  doc["camera"]["width"] = 800;
  doc["camera"]["height"] = 600;
  // The method's own defaults, not the scene's render block (fig3's names 800 Gaussian centres):
  // data/experiments/table2_gpu.json's scenes replace it too.
  doc["render"] = Json{{"method", c.method}, {"paper", c.paper}};
  doc["render"]["gpu_pipeline"] = raster ? "raster" : "compute";
  if (c.farField > 0) doc["render"]["far_field"] = c.farField;
  if (*c.render) doc["render"].update(Json::parse(c.render));
  const Json& b = doc["medium"]["bounds"];
  const Vec3 centre =
      0.5f * (Vec3(b["min"][0].get<float>(), b["min"][1].get<float>(), b["min"][2].get<float>()) +
              Vec3(b["max"][0].get<float>(), b["max"][1].get<float>(), b["max"][2].get<float>()));
  doc["lights"] = ringOfLights(doc["lights"][0], centre, lights);
  return doc;
}

std::string frameLabel(const FrameCase& c, const benchmark::State& state) {
  return std::string(c.scene) + " " + c.method + (c.paper ? " paper" : " defaults") +
         (c.farField > 0 ? " + far_field " + std::to_string(c.farField) : "") + ", " +
         std::to_string(state.range(2)) + " lights, " + (state.range(3) ? "raster" : "compute") +
         ", " + gpu::context().info().renderer;
}

double median(std::vector<double> v) {
  if (v.empty()) return 0.0;
  std::sort(v.begin(), v.end());
  return v.size() % 2 ? v[v.size() / 2] : 0.5 * (v[v.size() / 2 - 1] + v[v.size() / 2]);
}

/// Steady frames: one Renderer, light 0 moved every frame (density and samples kept), the image
/// left on the device (Renderer::keepImageOnDevice). Real time per frame is the wall time an
/// engine waits for a frame it does not read back; counters: gpu_ms (the median of the stats'
/// gpu_ms_total: GPU time from timer queries), host_waits (the largest over the frames).
/// Runs a frame benchmark's body; a scatterlab error (a device limit a case exceeds: a storage
/// buffer above what the device addresses in one block, ...) is the
/// benchmark's error row, not the end of the run: the GPU report's other frames still come.
template <class Body>
void reportingErrors(benchmark::State& state, Body&& body) {
  try {
    body(state);
  } catch (const Error& e) {
    state.SkipWithError(e.what());
  }
}

void steadyFrame(benchmark::State& state) {
  initialize();
  const FrameCase& c = kFrameCases[state.range(0)];
  const Json doc = frameScene(c, int(state.range(1)), int(state.range(2)), state.range(3) != 0);
  Renderer r(doc, SCATTERLAB_SOURCE_DIR "/data/scenes", "", "gpu");
  r.keepImageOnDevice(true);
  r.render();  // cold: the density, the samples and the programs
  const Json p0 = doc["lights"][0]["position"];
  std::vector<double> gpuMs;
  double waits = 0, dispatches = 0, tracer = 0, steps = 0, skipped = 0, farTerms = 0, samples = 0;
  int frame = 0;
  for (auto _ : state) {
    ++frame;
    r.set("lights.0.position=[" + std::to_string(p0[0].get<double>() + 0.002 * (frame % 5)) + "," +
          p0[1].dump() + "," + p0[2].dump() + "]");
    const RenderResult res = r.render();
    state.PauseTiming();  // the stats were read after the frame (GpuFrame::report)
    gpuMs.push_back(res.stats.extra.value("gpu_ms_total", 0.0));
    waits = std::max(waits, res.stats.extra.value("host_waits", 0.0));
    dispatches = res.stats.extra.value("dispatches", 0.0);
    tracer = res.stats.extra.value("tracer_invocations", 0.0);
    steps = res.stats.extra.value("march_steps", 0.0);
    skipped = res.stats.extra.value("march_steps_skipped", 0.0);
    farTerms = res.stats.extra.value("far_field_terms", 0.0);
    samples = double(res.stats.samples.value_or(0));
    state.ResumeTiming();
  }
  state.counters["gpu_ms"] = median(gpuMs);
  state.counters["far_terms"] = farTerms;  // A's far field: point-light terms of the last frame
  state.counters["host_waits"] = waits;
  state.counters["dispatches"] = dispatches;
  // The work of a frame (issue 34): the tracer's invocations, the march's steps looked up and
  // the share it jumped over in empty blocks.
  state.counters["tracer_inv"] = tracer;
  state.counters["samples"] =
      samples;  // the frame's samples (0 where none, or switched to per-voxel)
  state.counters["march_steps"] = steps;
  state.counters["skipped_pct"] = steps + skipped > 0 ? 100.0 * skipped / (steps + skipped) : 0.0;
  state.SetLabel("steady: " + frameLabel(c, state));
}

/// Cold frames, as `scatterlab render` and the harness draw them: a new method per frame
/// (density built, samples made, programs cached), the image read back. Counters as above, and
/// image_readback_ms.
void coldFrame(benchmark::State& state) {
  initialize();
  const FrameCase& c = kFrameCases[state.range(0)];
  const Scene s =
      parseScene(frameScene(c, int(state.range(1)), int(state.range(2)), state.range(3) != 0),
                 SCATTERLAB_SOURCE_DIR "/data/scenes");
  createMethod(s, "", "gpu")->render(s, nullptr);  // programs compiled outside the timing
  std::vector<double> gpuMs, readback;
  double waits = 0;
  for (auto _ : state) {
    const RenderResult res = createMethod(s, "", "gpu")->render(s, nullptr);
    benchmark::DoNotOptimize(res.image.pixels().data());
    state.PauseTiming();
    gpuMs.push_back(res.stats.extra.value("gpu_ms_total", 0.0));
    readback.push_back(res.stats.extra.value("image_readback_ms", 0.0));
    waits = std::max(waits, res.stats.extra.value("host_waits", 0.0));
    state.ResumeTiming();
  }
  state.counters["gpu_ms"] = median(gpuMs);
  state.counters["image_readback_ms"] = median(readback);
  state.counters["host_waits"] = waits;
  state.SetLabel("cold: " + frameLabel(c, state));
}

void BM_GpuSteadyFrame(benchmark::State& state) {
  if (needGpu(state)) reportingErrors(state, steadyFrame);
}

void BM_GpuColdFrame(benchmark::State& state) {
  if (needGpu(state)) reportingErrors(state, coldFrame);
}

/// Like gpuLoop, and adds each stage's mean GPU ms as a counter (per-stage times of a pipeline).
template <class Body>
void gpuStageLoop(benchmark::State& state, Body&& body) {
  std::vector<std::pair<std::string, double>> sums;
  int n = 0;
  for (auto _ : state) {
    gpu::StageTimer timer;
    body(timer);
    double ms = 0;
    const auto res = timer.results();
    for (const auto& [stage, t] : res) {
      ms += t;
      auto it = std::find_if(sums.begin(), sums.end(), [&](auto& p) { return p.first == stage; });
      if (it == sums.end())
        sums.emplace_back(stage, t);
      else
        it->second += t;
    }
    ++n;
    state.SetIterationTime(ms * 1e-3);
  }
  for (const auto& [stage, t] : sums) state.counters[stage + " ms"] = t / std::max(n, 1);
  state.SetLabel(gpu::context().info().renderer);
}

/// `gradient` on the GPU without density construction: 512 samples of the glow scene ->
/// volume tracer (S, ∇S) -> gradient splat -> slice march (view planes, 800×600).
void BM_GpuGradientPipeline512(benchmark::State& state) {
  if (!needGpu(state)) return;
  const Scene s = glowScene(int(state.range(0)));
  const gpu::Volume d = gpu::buildDensity(s);
  const float vox = s.medium.voxelSize();
  MarchSettings ms;
  ms.step = vox;
  gpuStageLoop(state, [&](gpu::StageTimer& t) {
    auto samples = samples512(s);
    gpu::VolumeTracerGpu({vox, vox}).evaluate(s, d, samples, true, &t);
    const gpu::Volume r = gpu::GradientSplatGpu().reconstruct(d, samples, s.medium.bounds,
                                                              s.medium.resolution, nullptr, &t);
    Image img = gpu::SliceMarcher(ms).integrate(s, d, r, &t);
    benchmark::DoNotOptimize(img.pixels().data());
  });
}

/// `adaptive` on the GPU on the spot-light shaft scene (data/scenes/shaft.json, uniform
/// density): 541 grid samples -> GPU dynamic sampling (ε 1e-4, default levels 16, 32, 64 up to
/// half the resolution) -> gradient splat -> slice march, 800×600.
void BM_GpuAdaptivePipeline(benchmark::State& state) {
  if (!needGpu(state)) return;
  initialize();
  Scene s = loadScene(SCATTERLAB_SOURCE_DIR "/data/scenes/shaft.json");
  const int res = int(state.range(0));
  s.medium.resolution = IVec3(res);
  s.camera.width = 800;
  s.camera.height = 600;
  const gpu::Volume d = gpu::buildDensity(s);
  const DensityGrid hd = gpu::readDensity(d);
  const Json samplerCfg{{"type", "grid"}, {"count", 541}};
  Params sp(samplerCfg, "sampler");
  auto sampler = samplers().get("grid", "sampler")(sp, s);
  const std::vector<RadianceSample> initial = sampler->generate(s, hd);
  const float vox = s.medium.voxelSize();
  DynamicSamplingSettings ds;
  ds.epsilon = 1e-4;
  ds.levels.clear();
  for (int l : {16, 32, 64})
    if (l <= res / 2) ds.levels.push_back(l);
  ds.delta1 = vox;
  MarchSettings ms;
  ms.step = vox;
  std::size_t count = 0;
  gpuStageLoop(state, [&](gpu::StageTimer& t) {
    const DynamicSamplingResult r = gpu::dynamicSamplingGpu(s, d, initial, {vox, vox}, ds, &t);
    count = r.samples.size();
    const gpu::Volume rad = gpu::GradientSplatGpu().reconstruct(d, r.samples, s.medium.bounds,
                                                                s.medium.resolution, nullptr, &t);
    Image img = gpu::SliceMarcher(ms).integrate(s, d, rad, &t);
    benchmark::DoNotOptimize(img.pixels().data());
  });
  state.counters["samples"] = double(count);
}

/// Iterations are fixed small so the suite finishes on llvmpipe; on a real GPU set
/// SCATTERLAB_GPU_BENCH_ITERS (e.g. 100) to run every GPU benchmark that many times.
int iters(int n) {
  const char* e = std::getenv("SCATTERLAB_GPU_BENCH_ITERS");
  return e && std::atoi(e) > 0 ? std::atoi(e) : n;
}

/// The GPU dynamic-sampling benchmarks' input: the shaft scene at resolution³, 541 grid
/// samples, ε 1e-4, levels 16, 32, 64 up to half the resolution.
struct DynamicSamplingInput {
  Scene scene;
  gpu::Volume density;
  std::vector<RadianceSample> initial;
  DynamicSamplingSettings settings;
  float voxel = 0.0f;

  explicit DynamicSamplingInput(int res) {
    initialize();
    scene = loadScene(SCATTERLAB_SOURCE_DIR "/data/scenes/shaft.json");
    scene.medium.resolution = IVec3(res);
    density = gpu::buildDensity(scene);
    const DensityGrid hd = gpu::readDensity(density);
    const Json samplerCfg{{"type", "grid"}, {"count", 541}};
    Params sp(samplerCfg, "sampler");
    initial = samplers().get("grid", "sampler")(sp, scene)->generate(scene, hd);
    voxel = scene.medium.voxelSize();
    settings.epsilon = 1e-4;
    settings.levels.clear();
    for (int l : {16, 32, 64})
      if (l <= res / 2) settings.levels.push_back(l);
    settings.delta1 = voxel;
  }
};

/// Wall-clock time of GPU dynamic sampling alone (DynamicSamplingInput), the result read back:
/// what the host waits for, read-backs and buffer creation included (issue 14: no per-level
/// read-back). With `kept`, as the GPU refiner runs it from the second frame on: its buffers
/// kept in a workspace (no buffer created).
void gpuDynamicSamplingWall(benchmark::State& state, bool kept) {
  if (!needGpu(state)) return;
  const DynamicSamplingInput in(int(state.range(0)));
  gpu::DynamicSamplingWorkspace workspace;
  std::size_t count = 0;
  for (auto _ : state) {
    const DynamicSamplingResult r =
        gpu::dynamicSamplingGpu(in.scene, in.density, in.initial, {in.voxel, in.voxel}, in.settings,
                                nullptr, nullptr, nullptr, kept ? &workspace : nullptr);
    glFinish();
    count = r.samples.size();
  }
  state.counters["samples"] = double(count);
  state.SetLabel(gpu::context().info().renderer);
}
void BM_GpuDynamicSamplingWall(benchmark::State& state) {
  gpuDynamicSamplingWall(state, false);
}
void BM_GpuDynamicSamplingWallKept(benchmark::State& state) {
  gpuDynamicSamplingWall(state, true);
}
BENCHMARK(BM_GpuDynamicSamplingWall)
    ->Arg(64)
    ->Arg(128)
    ->UseRealTime()
    ->Iterations(iters(3))
    ->Unit(benchmark::kMillisecond);
BENCHMARK(BM_GpuDynamicSamplingWallKept)
    ->Arg(64)
    ->Arg(128)
    ->UseRealTime()
    ->Iterations(iters(3))
    ->Unit(benchmark::kMillisecond);

/// smoke1.vdb fitted with 512 Gaussians (the .sog model of docs/benchmarks.md "Media").
const std::shared_ptr<const SogDensity>& smokeSog(const char* source) {
  static const SogModel model = [] {
    const DensityGrid g = loadVdbAsDense(SCATTERLAB_SOURCE_DIR "/data/vdb/smoke1.vdb", "density");
    SogFitOptions o;
    o.gaussians = 512;
    return fitSog(g, o);
  }();
  static const auto a = std::make_shared<const SogDensity>(model, "smoke1 (a)");
  static const auto b = std::make_shared<const SogDensity>(model, "smoke1 (b)");
  return source[0] == 'a' ? a : b;
}

/// The density volume (128³ over the model's lattice box) of a .sog medium on the GPU backend,
/// wall time until the texture is ready. Arg 0: CPU splat (SogModel::splat) + upload, what
/// gpu::buildDensity did before issue 14; 1: Gaussians splatted on the GPU, residual uploaded
/// sparsely (its entries) and scattered, then added (a model not seen before: two models with
/// the same data alternate); 2: the same with the residual lattice kept (the same model again,
/// e.g. a new transform or resolution).
void BM_GpuSogDensity128(benchmark::State& state) {
  if (!needGpu(state)) return;
  const int mode = int(state.range(0));
  const auto& sog = smokeSog("a");
  const Box bounds = sog->model().residual.bounds();
  const IVec3 dims(128);
  // Programs compiled outside the loop; with the residual kept, the model's lattice too.
  gpu::splatSog(mode == 2 ? sog : smokeSog("b"), bounds, dims);
  int i = 0, n = 0;
  std::map<std::string, double> stageMs;  // GPU ms per pass (llvmpipe: CPU time)
  for (auto _ : state) {
    if (mode == 0) {
      DensityGrid g(bounds, dims);
      sog->build(g);
      gpu::Volume v = gpu::uploadDensity(g);
      glFinish();
      benchmark::DoNotOptimize(v.texture.id());
    } else {
      const auto& m = mode == 1 ? smokeSog(i++ % 2 ? "b" : "a") : sog;
      gpu::StageTimer timer;
      gpu::Volume v = gpu::splatSog(m, bounds, dims, &timer);
      glFinish();
      benchmark::DoNotOptimize(v.texture.id());
      for (const auto& [stage, ms] : timer.results()) stageMs[stage] += ms;
      ++n;
    }
  }
  for (const auto& [stage, ms] : stageMs) state.counters[stage + " ms"] = ms / std::max(n, 1);
  const char* labels[] = {"cpu splat + upload", "gpu splat, residual uploaded",
                          "gpu splat, residual kept"};
  state.SetLabel(labels[mode]);
  state.counters["hash_entries"] = double(sog->model().residual.size());
}
BENCHMARK(BM_GpuSogDensity128)
    ->DenseRange(0, 2)
    ->UseRealTime()
    ->Iterations(iters(4))
    ->Unit(benchmark::kMillisecond);

BENCHMARK(BM_GpuDensitySplat)
    ->ArgsProduct({{64, 128}, {0, 1}})
    ->UseManualTime()
    ->Iterations(iters(3))
    ->Unit(benchmark::kMillisecond);
BENCHMARK(BM_GpuVolumeTracer512)
    ->Arg(64)
    ->Arg(128)
    ->UseManualTime()
    ->Iterations(iters(2))
    ->Unit(benchmark::kMillisecond);
BENCHMARK(BM_GpuGradientSplat512)
    ->ArgsProduct({{64, 128}, {0, 1}})
    ->UseManualTime()
    ->Iterations(iters(2))
    ->Unit(benchmark::kMillisecond);
/// Shadow maps of scene objects (docs/objects.md, GPU): rendering every light's layers and the
/// VSM blur, default settings (VSM 1024², filter 3). Arg: 0 window (ortho + cube: 7 layers),
/// 1 bunny_spot (one perspective map), 2 cornell_fog (one cube).
void BM_GpuShadowMaps(benchmark::State& state) {
  if (!needGpu(state)) return;
  initialize();
  const char* names[] = {"window", "bunny_spot", "cornell_fog"};
  Scene s;
  try {
    s = loadScene(std::string(SCATTERLAB_SOURCE_DIR) + "/data/scenes/" + names[state.range(0)] +
                  ".json");
  } catch (const IoError& e) {
    state.SkipWithError(e.what());
    return;
  }
  const gpu::ObjectGeometry geometry(*s.objects);
  gpuLoop(state, [&](gpu::StageTimer& t) {
    const gpu::ShadowMaps maps(s, geometry, ShadowMapSettings{}, &t);
    benchmark::DoNotOptimize(maps.layers());
  });
  state.SetLabel(std::string(names[state.range(0)]) + ", " + gpu::context().info().renderer);
}

BENCHMARK(BM_GpuShadowMaps)
    ->DenseRange(0, 2)
    ->UseManualTime()
    ->Iterations(iters(2))
    ->Unit(benchmark::kMillisecond);
BENCHMARK(BM_GpuPerVoxel)
    ->Arg(64)
    ->Arg(128)
    ->UseManualTime()
    ->Iterations(iters(1))
    ->Unit(benchmark::kMillisecond);
BENCHMARK(BM_GpuGradientPipeline512)
    ->Arg(64)
    ->Arg(128)
    ->UseManualTime()
    ->Iterations(iters(1))
    ->Unit(benchmark::kMillisecond);
BENCHMARK(BM_GpuAdaptivePipeline)
    ->Arg(64)
    ->Arg(128)
    ->UseManualTime()
    ->Iterations(iters(1))
    ->Unit(benchmark::kMillisecond);
BENCHMARK(BM_GpuSliceMarch800x600)
    ->Arg(64)
    ->Arg(128)
    ->UseManualTime()
    ->Iterations(iters(1))
    ->Unit(benchmark::kMillisecond);
BENCHMARK(BM_GpuViewMarch800x600)
    ->Arg(64)
    ->Arg(128)
    ->Arg(256)
    ->UseManualTime()
    ->Iterations(iters(1))
    ->Unit(benchmark::kMillisecond);
// Cases × {128³, 256³} × {1, 64} lights × compute (the far field steady only); the paper's
// gradient also raster.
BENCHMARK(BM_GpuSteadyFrame)
    ->ArgsProduct({{0, 1, 2, 3, 4, 5}, {128, 256}, {1, 64}, {0}})
    ->ArgsProduct({{0}, {128, 256}, {1}, {1}})
    ->UseRealTime()
    ->Iterations(iters(2))
    ->Unit(benchmark::kMillisecond);
BENCHMARK(BM_GpuColdFrame)
    ->ArgsProduct({{0, 1, 2, 3, 4}, {128, 256}, {1}, {0}})
    ->UseRealTime()
    ->Iterations(iters(1))
    ->Unit(benchmark::kMillisecond);
BENCHMARK(BM_GpuRendererFrameGradient512)
    ->ArgsProduct({{128, 256}, {0, 1}})
    ->UseRealTime()
    ->Iterations(iters(2))
    ->Unit(benchmark::kMillisecond);

}  // namespace
}  // namespace scatterlab
