#include "cpu/radiance_evaluator.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include "cpu/shadow_rays.h"
#include "shading/transport.h"

namespace scatterlab {

namespace {

/// `lit` (null: every sample traced): a sample it does not reach within its radius + `reach`
/// is not traced and holds `unlit` (TracerSteps::reach). A point without a sphere of validity
/// (radius 0: dynamic sampling's probes) is always traced.
template <class Source>
void evaluateWith(const Source& source, const Scene& scene, float delta2,
                  std::span<RadianceSample> samples, bool gradients, const LitReach* lit = nullptr,
                  float reach = 0.0f, Vec3 unlit = Vec3(0.0f)) {
  const Vec3 eye = scene.camera.position;
  const auto S = [&](const Vec3& p) { return source(p, towardsEye(eye, p)); };
  const float h = delta2, inv2h = 0.5f / delta2;
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, samples.size(), 16),
                    [&](const tbb::blocked_range<std::size_t>& r) {
                      for (std::size_t n = r.begin(); n < r.end(); ++n) {
                        RadianceSample& s = samples[n];
                        if (lit && s.radius > 0.0f && !lit->reaches(s.position, s.radius + reach)) {
                          s.S = unlit;
                          for (int a = 0; a < 3; ++a) s.dS[a] = Vec3(0.0f);
                          continue;
                        }
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

}  // namespace

void evaluateSamples(const Scene& scene, const DensityGrid& density, TracerSteps steps,
                     std::span<RadianceSample> samples, bool gradients) {
  const SimdShadowRays shadows(density);
  const ShadowDepthFn shadow = steps.simdShadows ? shadows.fn() : ShadowDepthFn{};
  const LitReach lit(scene.lights);
  const LitReach* skip =
      steps.factorLights && steps.reach > 0.0f && !lit.everywhere() ? &lit : nullptr;
  if (steps.logValues()) {
    const FactoredSourceRadiance v(scene, density, steps.delta1, steps.lampModel, shadow);
    const auto logV = [&](const Vec3& x, const Vec3& toViewer) {
      return glm::log(glm::max(v(x, toViewer), Vec3(kMinV)));
    };
    evaluateWith(logV, scene, steps.delta2, samples, gradients, skip, steps.reach,
                 Vec3(std::log(kMinV)));
  } else if (steps.factorLights)
    evaluateWith(FactoredSourceRadiance(scene, density, steps.delta1, steps.lampModel, shadow),
                 scene, steps.delta2, samples, gradients, skip, steps.reach);
  else
    evaluateWith(SourceRadiance(scene, density, steps.delta1, nullptr, steps.simdShadows, shadow),
                 scene, steps.delta2, samples, gradients);
}

namespace {

class VolumeTracerEvaluator : public RadianceEvaluator {
 public:
  explicit VolumeTracerEvaluator(TracerSteps s) : steps_(s) {}
  void evaluate(Frame& frame, const Scene& scene, std::span<RadianceSample> samples,
                bool gradients) override {
    evaluateSamples(scene, frame.hostDensity(), steps_, samples, gradients);
  }

 private:
  TracerSteps steps_;
};

/// The volume tracer's own key (its light-march step is the pipeline's delta1).
const std::vector<KeyDoc>& volumeTracerKeys() {
  static const std::vector<KeyDoc> keys = {
      {"delta2", "number", "one voxel edge", "(diag·1e-6, diag]",
       "central-difference step of ∇S (the paper's Δ2); methods with samples", "0.5"},
  };
  return keys;
}

void parseVolumeTracer(Params& p, const Scene& scene, PipelineSettings& s) {
  s.delta2 = p.real("delta2", scene.medium.voxelSize(),
                    stepRange(glm::length(scene.medium.bounds.extent())));
}

}  // namespace

void registerRadianceEvaluators() {
  radianceEvaluators().declare("volume-tracer", {.keys = {{volumeTracerKeys, parseVolumeTracer}}});
  radianceEvaluators().addVariant("volume-tracer", Backend::Cpu, [](const PipelineSettings& s) {
    return std::unique_ptr<RadianceEvaluator>(new VolumeTracerEvaluator(s.tracerSteps()));
  });
}

}  // namespace scatterlab
