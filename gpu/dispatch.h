#pragma once
/// Small helpers of every GL pass in gpu/: glm-typed uniforms and compute dispatch sizes.
/// The uniform setters need the program in use (glUniform* acts on the current program).

#include <cstddef>

#include "core/math.h"
#include "gpu/gl.h"

namespace scatterlab::gpu {

inline void setVec3(const Program& p, const char* name, const Vec3& v) {
  glUniform3f(p.uniform(name), v.x, v.y, v.z);
}

inline void setIVec3(const Program& p, const char* name, const IVec3& v) {
  glUniform3i(p.uniform(name), v.x, v.y, v.z);
}

/// Workgroups that cover `n` invocations with `size` per group (the last one partly idle).
inline GLuint groups(std::size_t n, GLuint size) {
  return GLuint((n + size - 1) / size);
}

}  // namespace scatterlab::gpu
