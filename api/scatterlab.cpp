#include "api/scatterlab.h"

#include <mutex>

#include "media/register.h"
#include "render/methods.h"

namespace scatterlab {

void initialize() {
  static std::once_flag once;
  std::call_once(once, [] {
    registerMediaModels();
    registerReferenceMethods();
  });
}

const char* version() {
  return SCATTERLAB_VERSION;
}

}  // namespace scatterlab
