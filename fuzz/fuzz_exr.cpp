// libFuzzer target: bytes as an .exr file → readExr (OpenEXR through scatterlab's reader).
// Built and run by scripts/fuzz.sh.

#include <unistd.h>

#include <cstddef>
#include <cstdint>
#include <fstream>
#include <string>

#include "core/error.h"
#include "core/image.h"

using namespace scatterlab;

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  static const std::string path = "/tmp/fuzz_exr_" + std::to_string(::getpid()) + ".exr";
  std::ofstream(path, std::ios::binary | std::ios::trunc)
      .write(reinterpret_cast<const char*>(data), std::streamsize(size));
  try {
    (void)readExr(path);
  } catch (const Error&) {
  }
  return 0;
}
