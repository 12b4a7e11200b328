#include "core/stages.h"

namespace scatterlab {

Registry<StageFactory<Sampler>>& samplers() {
  static Registry<StageFactory<Sampler>> r("sampler");
  return r;
}
Registry<StageFactory<RadianceEvaluator>>& radianceEvaluators() {
  static Registry<StageFactory<RadianceEvaluator>> r("radiance evaluator");
  return r;
}
Registry<StageFactory<Reconstruction>>& reconstructions() {
  static Registry<StageFactory<Reconstruction>> r("reconstruction");
  return r;
}
Registry<StageFactory<Integrator>>& integrators() {
  static Registry<StageFactory<Integrator>> r("integrator");
  return r;
}

}  // namespace scatterlab
