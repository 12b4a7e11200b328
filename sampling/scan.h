#pragma once
/// Scan compaction (Harris et al., GPU Gems 3 ch. 39; paper Sec. 5): an exclusive prefix sum of
/// 0/1 flags gives every flagged element its slot in the compacted output. CPU variant with
/// tbb::parallel_scan; the GPU variant (compute shader) has the same semantics, so both produce
/// the same order: ascending index.

#include <cstdint>
#include <span>
#include <vector>

namespace scatterlab {

/// offsets[i] = number of non-zero flags before i. Returns the total. Sizes must match.
std::uint32_t exclusiveScan(std::span<const std::uint8_t> flags, std::span<std::uint32_t> offsets);

/// Indices i with flags[i] != 0, ascending (scan, then scatter).
std::vector<std::uint32_t> compactFlags(std::span<const std::uint8_t> flags);

}  // namespace scatterlab
