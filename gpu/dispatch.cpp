#include "gpu/dispatch.h"

#include <algorithm>
#include <array>
#include <string>

#include "core/error.h"

namespace scatterlab::gpu {

namespace {

PassCounts counts;
GLuint fold = kLeastWorkGroupCount;

/// GL_MAX_COMPUTE_WORK_GROUP_COUNT per axis of the current context (read once per process:
/// the context lives until exit).
const std::array<GLint, 3>& maxGroups() {
  static const std::array<GLint, 3> max = [] {
    std::array<GLint, 3> m{};
    for (GLuint a = 0; a < 3; ++a) glGetIntegeri_v(GL_MAX_COMPUTE_WORK_GROUP_COUNT, a, &m[a]);
    return m;
  }();
  return max;
}

void countPass(std::map<std::string, long long, std::less<>>& m, std::string_view pass,
               long long n) {
  if (const auto it = m.find(pass); it != m.end())
    it->second += n;
  else
    m.emplace(std::string(pass), n);
}

}  // namespace

PassCounts passCounts() {
  return counts;
}

UVec3 linearDispatch(GLuint groupCount) {
  if (groupCount <= fold) return UVec3(groupCount, 1, 1);
  return UVec3(fold, (groupCount + fold - 1) / fold, 1);
}

GLuint linearFold() {
  return fold;
}

void setLinearFoldForTesting(GLuint f) {
  fold = f == 0 ? kLeastWorkGroupCount : std::min(f, kLeastWorkGroupCount);
}

void dispatch(std::string_view pass, UVec3 count, StageTimer* timer) {
  if (count.x == 0 || count.y == 0 || count.z == 0) return;
  const std::array<GLint, 3>& max = maxGroups();
  for (int a = 0; a < 3; ++a)
    if (count[a] > GLuint(max[std::size_t(a)]))
      throw GpuError(std::string(pass) + ": " + std::to_string(count[a]) + " workgroups along " +
                     "xyz"[a] + " exceed this device's GL_MAX_COMPUTE_WORK_GROUP_COUNT of " +
                     std::to_string(max[std::size_t(a)]));
  {
    ScopedGpuTimer t(timer, std::string(pass));
    glDispatchCompute(count.x, count.y, count.z);
  }
  ++counts.dispatches;
  countPass(counts.byPass, pass, 1);
  const long long n = (long long)count.x * count.y * count.z * currentProgramLocalSize();
  countPass(counts.invocations, pass, n);
  checkGl(pass);
}

void dispatchIndirect(std::string_view pass, GLintptr offset, StageTimer* timer) {
  {
    ScopedGpuTimer t(timer, std::string(pass));
    glDispatchComputeIndirect(offset);
  }
  ++counts.dispatches;
  ++counts.indirect;
  countPass(counts.byPass, pass, 1);
  checkGl(pass);
}

void dispatchLightParts(const Program& program, int parts, std::string_view pass, UVec3 count,
                        GLbitfield barrier, StageTimer* timer) {
  glUniform1i(program.uniform("uLightStride"), parts);
  for (int part = 0; part < parts; ++part) {
    glUniform1i(program.uniform("uLightFirst"), part);
    dispatch(pass, count, timer);
    glMemoryBarrier(barrier);
  }
}

}  // namespace scatterlab::gpu
