#include "api/scatterlab.h"

#include <mutex>

#include "cpu/integrators.h"
#include "cpu/interpolation.h"
#include "cpu/radiance_evaluator.h"
#include "media/register.h"
#include "methods/register.h"
#include "sampling/dynamic_sampling.h"
#include "sampling/samplers.h"
#ifdef SCATTERLAB_HAS_GPU
#include "gpu/register.h"
#endif

namespace scatterlab {

void initialize() {
  static std::once_flag once;
  std::call_once(once, [] {
    // Stage variants first (CPU, then the GPU ones beside them), then the methods that
    // compose them.
    registerMediaModels();
    registerSamplers();
    registerRadianceEvaluators();
    registerRefiners();
    registerReconstructions();
    registerIntegrators();
#ifdef SCATTERLAB_HAS_GPU
    gpu::registerGpuStages();
#endif
    registerMethods();
  });
}

const char* version() {
  return SCATTERLAB_VERSION;
}

}  // namespace scatterlab
