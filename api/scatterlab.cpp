#include "api/scatterlab.h"

#include <mutex>

#include "media/register.h"
#include "render/interpolation.h"
#include "render/methods.h"
#include "render/radiance_evaluator.h"
#include "render/sampled_methods.h"
#include "sampling/samplers.h"
#ifdef SCATTERLAB_HAS_GPU
#include "gpu/register.h"
#endif

namespace scatterlab {

void initialize() {
  static std::once_flag once;
  std::call_once(once, [] {
    registerMediaModels();
    registerReferenceMethods();
    registerSamplers();
    registerRadianceEvaluators();
    registerReconstructions();
    registerSampledMethods();
#ifdef SCATTERLAB_HAS_GPU
    gpu::registerGpuStages();
#endif
  });
}

const char* version() {
  return SCATTERLAB_VERSION;
}

}  // namespace scatterlab
