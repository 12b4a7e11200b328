#include "gpu/scan.h"

#include <algorithm>

#include "core/error.h"
#include "gpu/bindings.h"
#include "gpu/context.h"
#include "gpu/dispatch.h"
#include "gpu/shaders.h"

namespace scatterlab::gpu {

namespace {

constexpr GLuint kScanBlock = 512;  // elements per workgroup of scan.comp.glsl

const Program& scanProgram() {
  return program({.compute = {"scan.comp.glsl"}}, "scan (block)");
}
const Program& scanAddProgram() {
  return program({.compute = {"scan.comp.glsl"}, .defines = {"SL_SCAN_ADD"}},
                 "scan (add block sums)");
}

/// scanBuffer at recursion depth `depth`: the block sums of depth d live in sums[2d] (and their
/// scan in sums[2d + 1]); the vector is sized before the recursion, which holds references
/// into it.
void scanAt(const Buffer& in, const Buffer& out, GLuint n, bool flags, ScanScratch& sums,
            std::size_t depth) {
  if (n == 0) return;
  const GLuint blocks = groups(n, kScanBlock);
  if (depth == 0) {
    std::size_t depths = 1;
    for (GLuint m = blocks; m > 1; m = groups(m, kScanBlock)) ++depths;
    if (sums.size() < 2 * depths) sums.resize(2 * depths);
  }
  Buffer& blockSums = sums[2 * depth];
  ensure(blockSums, blocks * sizeof(GLuint), "scan block sums");
  const Program& scan = scanProgram();
  scan.use();
  glUniform1ui(scan.uniform("uCount"), n);
  glUniform1i(scan.uniform("uFlags"), flags ? 1 : 0);
  in.bindBase(GL_SHADER_STORAGE_BUFFER, binding::kScanIn);
  out.bindBase(GL_SHADER_STORAGE_BUFFER, binding::kScanOut);
  blockSums.bindBase(GL_SHADER_STORAGE_BUFFER, binding::kScanBlockSums);
  dispatch("scan (block)", linearDispatch(blocks));
  glMemoryBarrier(GL_SHADER_STORAGE_BARRIER_BIT);
  if (blocks > 1) {
    ensure(sums[2 * depth + 1], blocks * sizeof(GLuint), "scanned block sums");
    scanAt(sums[2 * depth], sums[2 * depth + 1], blocks, false, sums, depth + 1);
    const Program& add = scanAddProgram();
    add.use();
    glUniform1ui(add.uniform("uCount"), n);
    out.bindBase(GL_SHADER_STORAGE_BUFFER, binding::kScanOut);
    sums[2 * depth + 1].bindBase(GL_SHADER_STORAGE_BUFFER, binding::kScanScannedSums);
    dispatch("scan (add block sums)", linearDispatch(blocks));
    glMemoryBarrier(GL_SHADER_STORAGE_BARRIER_BIT);
  }
}

}  // namespace

void ensure(Buffer& buffer, std::size_t bytes, const std::string& label, Growth growth) {
  bytes = std::max<std::size_t>(bytes, 4);
  if (buffer.extendTo(bytes)) return;
  // A buffer that grows takes headroom; the first one too where its size varies per frame.
  const std::size_t size = buffer || growth == Growth::Varies ? Buffer::grownFor(bytes) : bytes;
  buffer = Buffer();  // the old storage goes back to the recycler first
  buffer = Buffer(size, nullptr, GL_DYNAMIC_STORAGE_BIT, label);
}

void scanBuffer(const Buffer& in, const Buffer& out, GLuint n, bool flags, ScanScratch& sums) {
  scanAt(in, out, n, flags, sums, 0);
}

std::uint32_t exclusiveScanGpu(std::span<const std::uint8_t> flags,
                               std::span<std::uint32_t> offsets) {
  context();
  if (flags.size() != offsets.size()) throw GpuError("exclusiveScanGpu: size mismatch");
  const GLuint n = GLuint(flags.size());
  if (n == 0) return 0;
  const std::vector<GLuint> wide(flags.begin(), flags.end());
  const Buffer in(n * sizeof(GLuint), wide.data(), 0, "scan flags");
  const Buffer out(n * sizeof(GLuint), nullptr, 0, "scan offsets");
  ScanScratch sums;
  scanBuffer(in, out, n, true, sums);
  checkGl("scan");
  out.read(offsets.data(), n * sizeof(GLuint));
  return offsets[n - 1] + (flags[n - 1] != 0 ? 1u : 0u);
}

}  // namespace scatterlab::gpu
