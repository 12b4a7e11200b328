#pragma once
/// The pass layer of gpu/ (docs/methods.md, "A GPU stage"): glm-typed uniforms, compute
/// dispatches that are checked, counted and timed, and dispatch sizes. Every pass in gpu/
/// dispatches through dispatch() / dispatchIndirect(), never glDispatchCompute directly.
/// The uniform setters need the program in use (glUniform* acts on the current program);
/// Program::uniform resolves the name once per program and throws on a name no source declares.

#include <cstddef>
#include <map>
#include <string>
#include <string_view>

#include "core/math.h"
#include "gpu/gl.h"
#include "gpu/timer.h"

namespace scatterlab::gpu {

inline void setVec3(const Program& p, std::string_view name, const Vec3& v) {
  glUniform3f(p.uniform(name), v.x, v.y, v.z);
}

inline void setIVec3(const Program& p, std::string_view name, const IVec3& v) {
  glUniform3i(p.uniform(name), v.x, v.y, v.z);
}

/// Workgroups that cover `n` invocations with `size` per group (the last one partly idle).
inline GLuint groups(std::size_t n, GLuint size) {
  return GLuint((n + size - 1) / size);
}

/// The least GL_MAX_COMPUTE_WORK_GROUP_COUNT of any axis GL 4.5 allows (llvmpipe's and Intel's
/// x; NVIDIA's x is 2³¹ − 1, its y and z this).
inline constexpr GLuint kLeastWorkGroupCount = 65535;

/// A one-dimensional pass of `groupCount` workgroups laid out so that no axis exceeds
/// kLeastWorkGroupCount: (n, 1, 1) up to it, else rows of linearFold() = 65535 workgroups,
/// (65535, ⌈n / 65535⌉, 1), the last row partly past the end. Its shaders index with
/// SL_LINEAR_GROUP / SL_LINEAR_INVOCATION (every compute shader's prologue, gpu/shaders.cpp) and
/// return past their count (a whole workgroup at once where they use barriers); a pass whose
/// size the GPU writes (dynamic_level.comp.glsl) folds at the same linearFold().
UVec3 linearDispatch(GLuint groupCount);
/// The row length of linearDispatch: kLeastWorkGroupCount, or what setLinearFoldForTesting set
/// (a short row makes every 1D pass of a small test scene span two axes, as a 256³ one does).
GLuint linearFold();
void setLinearFoldForTesting(GLuint fold);  ///< 0: back to kLeastWorkGroupCount

/// What has been sent to the GPU through the pass layer since the process started (no
/// context): the stats count them per frame as differences.
struct PassCounts {
  long long dispatches = 0;  ///< compute dispatches, direct and indirect
  long long indirect = 0;    ///< of which indirect (sizes written on the GPU)
  /// Invocations of the direct dispatches per pass (workgroups × the program's workgroup
  /// size; an indirect dispatch's sizes are known only on the GPU and are not counted).
  std::map<std::string, long long, std::less<>> invocations;
  /// Dispatches per pass, direct and indirect.
  std::map<std::string, long long, std::less<>> byPass;
};
PassCounts passCounts();

/// Dispatches `count` workgroups of the program in use (made current by Program::use), as pass
/// `pass`: a size over the device's GL_MAX_COMPUTE_WORK_GROUP_COUNT is a GpuError naming the pass
/// and the limit before any work (never a silently clipped image); a GL error after it is a
/// GpuError naming the pass (checkGl). Timed as `pass` into `timer` when one is given (the caller
/// must not be inside a ScopedGpuTimer of the same timer: stages do not nest). An empty size is no
/// work.
void dispatch(std::string_view pass, UVec3 count, StageTimer* timer = nullptr);
/// Same, with the sizes read by the GPU from the GL_DISPATCH_INDIRECT_BUFFER bound, at byte
/// `offset` (no size check: the shader that wrote them keeps them within the limit).
void dispatchIndirect(std::string_view pass, GLintptr offset, StageTimer* timer = nullptr);
/// A pass whose lights are split over `parts` dispatches (lightDispatches, gpu/shaders.h):
/// `program` (in use, declaring uLightFirst and uLightStride) gets uLightStride = parts, then for
/// each part c uLightFirst = c, the dispatch of `count` as `pass` and `barrier`, so that each
/// part adds to what the ones before it stored. `parts` 1: one dispatch, as without a split.
void dispatchLightParts(const Program& program, int parts, std::string_view pass, UVec3 count,
                        GLbitfield barrier, StageTimer* timer = nullptr);

}  // namespace scatterlab::gpu
