// libFuzzer target: bytes as a .sog file → readSog (header, sizes, checksum, Gaussians, keys),
// then one evaluation of the model. Built and run by scripts/fuzz.sh. The checksum rejects
// almost every mutation, so the target also feeds the bytes with the checksum recomputed.

#include <unistd.h>

#include <cstddef>
#include <cstdint>
#include <cstring>
#include <fstream>
#include <string>

#include "core/error.h"
#include "media/sog.h"

using namespace scatterlab;

namespace {

const std::string& path() {
  static const std::string p = "/tmp/fuzz_sog_" + std::to_string(::getpid()) + ".sog";
  return p;
}

void tryRead(const std::string& bytes) {
  std::ofstream(path(), std::ios::binary | std::ios::trunc)
      .write(bytes.data(), std::streamsize(bytes.size()));
  try {
    const SogModel m = readSog(path());
    (void)m.eval(Vec3(0.5f));
  } catch (const Error&) {
  }
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  std::string s(reinterpret_cast<const char*>(data), size);
  tryRead(s);
  if (s.size() > 8) {  // FNV-1a 64 of everything before the last 8 bytes
    std::uint64_t h = 14695981039346656037ull;
    for (std::size_t i = 0; i + 8 < s.size(); ++i) {
      h ^= std::uint8_t(s[i]);
      h *= 1099511628211ull;
    }
    std::memcpy(s.data() + s.size() - 8, &h, 8);
    tryRead(s);
  }
  return 0;
}
