#include "core/stages.h"

namespace scatterlab {

const char* backendName(Backend b) {
  static constexpr std::array<const char*, kBackendCount> names = {"cpu", "gpu"};
  return names[std::size_t(b)];
}

void HostFrame::buildDensity(const Scene& scene) {
  density = std::make_shared<DensityGrid>(buildDensityVolume(scene));
}

DensityGrid buildDensityVolume(const Scene& scene) {
  DensityGrid g(scene.medium.bounds, scene.medium.resolution);
  scene.medium.density->build(g);
  return g;
}

void HostFrame::report(RenderStats& stats) {
  stats.backend = "cpu";
  stats.device = "CPU (TBB)";
  if (marchSteps) {
    stats.extra["march_steps"] = (*marchSteps)[0];
    stats.extra["march_steps_skipped"] = (*marchSteps)[1];
  }
}

std::array<BackendEntry, kBackendCount>& backends() {
  static std::array<BackendEntry, kBackendCount> b = [] {
    std::array<BackendEntry, kBackendCount> a;
    a[int(Backend::Cpu)].makeFrame = [](const PipelineSettings&) {
      return std::unique_ptr<Frame>(new HostFrame());
    };
    a[int(Backend::Cpu)].preferred = [](std::string*) { return false; };
    return a;
  }();
  return b;
}

Registry<StageFactory<Sampler>>& samplers() {
  static Registry<StageFactory<Sampler>> r("sampler");
  return r;
}
StageRegistry<EvaluatorMaker>& radianceEvaluators() {
  static StageRegistry<EvaluatorMaker> r("radiance evaluator");
  return r;
}
StageRegistry<ReconstructionMaker>& reconstructions() {
  static StageRegistry<ReconstructionMaker> r("reconstruction");
  return r;
}
StageRegistry<IntegratorMaker>& integrators() {
  static StageRegistry<IntegratorMaker> r("integrator");
  return r;
}

}  // namespace scatterlab
