#include "render/radiance_evaluator.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include "render/volume_tracer.h"

namespace scatterlab {

TracerSteps parseTracerSteps(Params& p, const Scene& scene) {
  const float voxel = scene.medium.voxelSize();
  const float ext = glm::length(scene.medium.bounds.extent());
  const Interval range{ext * 1e-6, ext, true, false};  // same bounds as parseMarchParams
  TracerSteps s;
  s.delta1 = p.real("delta1", voxel, range);
  s.delta2 = p.real("delta2", voxel, range);
  return s;
}

void evaluateSamples(const Scene& scene, const DensityGrid& density, TracerSteps steps,
                     std::span<RadianceSample> samples, bool gradients) {
  const SourceRadiance source(scene, density, steps.delta1);
  const Vec3 eye = scene.camera.position;
  const auto S = [&](const Vec3& p) {
    const Vec3 v = eye - p;
    const float len = glm::length(v);
    return source(p, len > 0.0f ? v / len : Vec3(0, 0, 1));
  };
  const float h = steps.delta2, inv2h = 0.5f / steps.delta2;
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, samples.size(), 16),
                    [&](const tbb::blocked_range<std::size_t>& r) {
                      for (std::size_t n = r.begin(); n < r.end(); ++n) {
                        RadianceSample& s = samples[n];
                        s.S = S(s.position);
                        for (int a = 0; a < 3; ++a) {
                          if (!gradients) {
                            s.dS[a] = Vec3(0.0f);
                            continue;
                          }
                          Vec3 e(0.0f);
                          e[a] = h;
                          s.dS[a] = (S(s.position + e) - S(s.position - e)) * inv2h;
                        }
                      }
                    });
}

namespace {

class VolumeTracerEvaluator : public RadianceEvaluator {
 public:
  explicit VolumeTracerEvaluator(TracerSteps s) : steps_(s) {}
  void evaluate(const Scene& scene, const DensityGrid& density, std::span<RadianceSample> samples,
                bool gradients) override {
    evaluateSamples(scene, density, steps_, samples, gradients);
  }

 private:
  TracerSteps steps_;
};

}  // namespace

void registerRadianceEvaluators() {
  radianceEvaluators().add("volume-tracer", [](Params& p, const Scene& scene) {
    return std::unique_ptr<RadianceEvaluator>(
        new VolumeTracerEvaluator(parseTracerSteps(p, scene)));
  });
}

}  // namespace scatterlab
