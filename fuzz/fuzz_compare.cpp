// libFuzzer target: bytes as an .exr file → readExr twice, readExrAttributes, compareImages of the
// image against itself (what `compare` and `info` do). Besides crashes it checks two properties an
// uninitialised pixel breaks (issue 37: a reader that could not fill every pixel returned freed
// memory, so `compare e.exr e.exr` reported 100 %): two reads of one file give the same bits, and
// an image against itself is 0 % off. Built and run by scripts/fuzz.sh.

#include <unistd.h>

#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <string>

#include "core/error.h"
#include "core/image.h"

using namespace scatterlab;

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  static const std::string path = "/tmp/fuzz_compare_" + std::to_string(::getpid()) + ".exr";
  std::ofstream(path, std::ios::binary | std::ios::trunc)
      .write(reinterpret_cast<const char*>(data), std::streamsize(size));
  try {
    (void)readExrAttributes(path);
  } catch (const Error&) {
  }
  try {
    const Image a = readExr(path);
    const Image b = readExr(path);
    if (a.width() != b.width() || a.height() != b.height() ||
        std::memcmp(a.pixels().data(), b.pixels().data(), a.pixels().size() * sizeof(Vec3)) != 0) {
      std::fprintf(stderr, "two reads of one EXR differ\n");
      std::abort();
    }
    const ImageError e = compareImages(a, b);
    if (e.relL2 != 0.0 && !std::isnan(e.relL2)) {
      std::fprintf(stderr, "an image against itself: relative L2 %g\n", e.relL2);
      std::abort();
    }
  } catch (const Error&) {
  }
  return 0;
}
