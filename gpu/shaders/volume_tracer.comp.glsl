// Radiance evaluator (paper Sec. 4): S and, with SL_GRADIENTS, the central-difference
// gradient (step uDelta2) for every sample in one dispatch. One invocation per sample.
layout(local_size_x = 64) in;

layout(std430, binding = 1) readonly buffer Positions { vec4 positions[]; };  // xyz
// Per sample four vec4: S, dS/dx, dS/dy, dS/dz (rgb).
layout(std430, binding = 2) writeonly buffer Results { vec4 results[]; };
uniform uint uCount;
uniform float uDelta2;

void main() {
  uint i = gl_GlobalInvocationID.x;
  if (i >= uCount) return;
  vec3 p = positions[i].xyz;
  results[4u * i] = vec4(sourceTowardsEye(p), 0.0);
#ifdef SL_GRADIENTS
  for (int a = 0; a < 3; ++a) {
    vec3 e = vec3(0.0);
    e[a] = uDelta2;
    vec3 g = (sourceTowardsEye(p + e) - sourceTowardsEye(p - e)) / (2.0 * uDelta2);
    results[4u * i + 1u + uint(a)] = vec4(g, 0.0);
  }
#else
  results[4u * i + 1u] = vec4(0.0);
  results[4u * i + 2u] = vec4(0.0);
  results[4u * i + 3u] = vec4(0.0);
#endif
}
