#include "api/scatterlab.h"

#include <mutex>

#include "media/register.h"
#include "render/methods.h"
#ifdef SCATTERLAB_HAS_GPU
#include "gpu/register.h"
#endif

namespace scatterlab {

void initialize() {
  static std::once_flag once;
  std::call_once(once, [] {
    registerMediaModels();
    registerReferenceMethods();
#ifdef SCATTERLAB_HAS_GPU
    gpu::registerGpuStages();
#endif
  });
}

const char* version() {
  return SCATTERLAB_VERSION;
}

}  // namespace scatterlab
