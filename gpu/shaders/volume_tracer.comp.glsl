// Radiance evaluator (paper Sec. 4): S and, with SL_GRADIENTS, the central-difference
// gradient (step uDelta2) for every sample in one dispatch. One invocation per sample.
layout(local_size_x = 64) in;

layout(std430, binding = BINDING_SAMPLES) readonly buffer Positions { vec4 positions[]; };  // xyz
layout(std430, binding = BINDING_RADIANCE) writeonly buffer Results { RadianceRecord results[]; };
uniform uint uCount;
uniform float uDelta2;

void main() {
  uint i = gl_GlobalInvocationID.x;
  if (i >= uCount) return;
  vec3 p = positions[i].xyz;
  results[i].S = vec4(sourceTowardsEye(p), 0.0);
#ifdef SL_GRADIENTS
  for (int a = 0; a < 3; ++a) {
    vec3 e = vec3(0.0);
    e[a] = uDelta2;
    vec3 g = (sourceTowardsEye(p + e) - sourceTowardsEye(p - e)) / (2.0 * uDelta2);
    results[i].dS[a] = vec4(g, 0.0);
  }
#else
  for (int a = 0; a < 3; ++a) results[i].dS[a] = vec4(0.0);
#endif
}
