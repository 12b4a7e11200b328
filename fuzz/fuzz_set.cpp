// libFuzzer target: `--set key.path=VALUE` (applyOverride) on a small scene-like document.
// Built and run by scripts/fuzz.sh.

#include <cstddef>
#include <cstdint>
#include <string>

#include "core/error.h"
#include "core/params.h"

using namespace scatterlab;

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  Json doc = {{"camera", {{"position", {0.5, 0.5, -2}}}}, {"lights", Json::array()}};
  try {
    applyOverride(doc, std::string(reinterpret_cast<const char*>(data), size));
    (void)describeValue(doc);
    Params p(doc, "");
    (void)p.vec3("camera");
  } catch (const Error&) {
  }
  return 0;
}
