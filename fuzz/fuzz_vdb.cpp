// libFuzzer target: bytes as a .vdb file → VdbDensity::load (layout check in this process,
// OpenVDB's parse in a forked child, the re-serialised grids parsed here). A crash of the
// child is an IoError by design; a crash of this process is a finding. Built and run by
// scripts/fuzz.sh.

#include <unistd.h>

#include <cstddef>
#include <cstdint>
#include <fstream>
#include <string>

#include "core/error.h"
#include "media/vdb.h"

using namespace scatterlab;

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  static const std::string path = "/tmp/fuzz_vdb_" + std::to_string(::getpid()) + ".vdb";
  std::ofstream(path, std::ios::binary | std::ios::trunc)
      .write(reinterpret_cast<const char*>(data), std::streamsize(size));
  try {
    const auto d = VdbDensity::load(path, "density");
    (void)d->eval(Vec3(0.0f));
  } catch (const Error&) {
  }
  return 0;
}
