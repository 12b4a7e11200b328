#include "sampling/scan.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_scan.h>

#include <stdexcept>

namespace scatterlab {

std::uint32_t exclusiveScan(std::span<const std::uint8_t> flags, std::span<std::uint32_t> offsets) {
  if (flags.size() != offsets.size()) throw std::invalid_argument("exclusiveScan: size mismatch");
  return tbb::parallel_scan(
      tbb::blocked_range<std::size_t>(0, flags.size(), 4096), std::uint32_t(0),
      [&](const tbb::blocked_range<std::size_t>& r, std::uint32_t sum, bool isFinal) {
        for (std::size_t i = r.begin(); i < r.end(); ++i) {
          if (isFinal) offsets[i] = sum;
          sum += flags[i] ? 1u : 0u;
        }
        return sum;
      },
      [](std::uint32_t a, std::uint32_t b) { return a + b; });
}

std::vector<std::uint32_t> compactFlags(std::span<const std::uint8_t> flags) {
  std::vector<std::uint32_t> offsets(flags.size());
  const std::uint32_t n = exclusiveScan(flags, offsets);
  std::vector<std::uint32_t> out(n);
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, flags.size(), 4096),
                    [&](const tbb::blocked_range<std::size_t>& r) {
                      for (std::size_t i = r.begin(); i < r.end(); ++i)
                        if (flags[i]) out[offsets[i]] = std::uint32_t(i);
                    });
  return out;
}

}  // namespace scatterlab
