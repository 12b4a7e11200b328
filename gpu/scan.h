#pragma once
/// Exclusive scan on the GPU (gpu/shaders/scan.comp.glsl: Blelloch's work-efficient scan, 512
/// elements per workgroup, the block sums scanned recursively): the compaction of dynamic
/// sampling's grid information buffers and of its final sample list, and the GPU-built sphere
/// bins. Everything here needs a GL context.

#include <cstdint>
#include <span>
#include <string>
#include <vector>

#include "gpu/gl.h"

namespace scatterlab::gpu {

/// How a buffer kept between frames is sized (ensure): `Fixed`: the first one holds what is
/// asked; `Varies`: its size follows a count that changes from frame to frame (a sample set, its
/// bins), so the first one takes Buffer::grownFor's headroom as well.
enum class Growth { Fixed, Varies };

/// `buffer` with at least `bytes` of storage (re-created only when smaller, never shrunk; a
/// re-created one gets Buffer::grownFor's headroom). Dynamic storage, so that the host may update
/// it (glNamedBufferSubData). Its contents are undefined after a call.
void ensure(Buffer& buffer, std::size_t bytes, const std::string& label,
            Growth growth = Growth::Fixed);

/// Scratch of scanBuffer: the block sums per recursion depth, grown as needed and kept.
using ScanScratch = std::vector<Buffer>;

/// Exclusive scan of the first n uints of `in` into `out`; with `flags` an element counts as
/// one when non-zero. Enqueued only (no wait); `out` is ready after the barrier it ends with.
/// n is a capacity known on the host: elements past the live count must read 0.
void scanBuffer(const Buffer& in, const Buffer& out, GLuint n, bool flags, ScanScratch& sums);

/// Exclusive scan of 0/1 flags by compute shader, on host data (upload, scan, read back), for
/// comparison with scatterlab::exclusiveScan. Returns the total.
std::uint32_t exclusiveScanGpu(std::span<const std::uint8_t> flags,
                               std::span<std::uint32_t> offsets);

}  // namespace scatterlab::gpu
