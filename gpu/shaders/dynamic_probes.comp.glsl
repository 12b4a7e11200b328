// Dynamic sampling, pass 2 of 3 (dynamic_error.comp.glsl has the whole): one invocation per
// sample j of the current level (x) and group g of kProbeGroup probes (the workgroup's y): the
// sum over the group's probes x_i = x_j + R_j·d_i of mean_RGB|L̃(x_i) − L(x_i)|·D(x_i), L̃ the
// sample's Taylor estimate (S and ∇S from pass 1), L the traced S, D the density; in probe
// order, as localShadingError (sampling/dynamic_sampling.cpp) sums each group. With SL_WEIGHT_A
// each probe's |L̃ − L| is multiplied per channel by A at the probe (lightFactorTowardsEye).
layout(local_size_x = 64) in;

layout(std430, binding = BINDING_SAMPLES) readonly buffer Samples { vec4 samples[]; };  // xyz, valid radius
layout(std430, binding = BINDING_RADIANCE) readonly buffer Results { RadianceRecord results[]; };
layout(std430, binding = BINDING_LEVEL_COUNTS) readonly buffer LevelCounts { uint counts[]; };
layout(std430, binding = BINDING_PROBE_SUMS) writeonly buffer ProbeSums { float probeSums[]; };

uniform uint uLevel;            // k: the level's sample count is counts[k]
uniform int uProbes;            // 6, 14, 26 or 40
uniform int uProbeGroup;        // kProbeGroup: probes per group
uniform vec3 uProbeDirs[40];    // probeOffsets() of the CPU
#ifdef SL_BOUNDED
uniform vec2 uTaylorBounds;     // TaylorBounds (lo, hi): the Taylor estimate is clamped to it
#endif

void main() {
  uint j = gl_GlobalInvocationID.x;
  if (j >= counts[uLevel]) return;
  int g = int(gl_WorkGroupID.y);
  vec4 pr = samples[j];
  vec3 x = pr.xyz;
  float R = pr.w;
  vec3 S = results[j].S.xyz;
  vec3 dS0 = results[j].dS[0].xyz, dS1 = results[j].dS[1].xyz, dS2 = results[j].dS[2].xyz;
  precise float sum = 0.0;
  int end = min(uProbes, (g + 1) * uProbeGroup);
  for (int i = g * uProbeGroup; i < end; ++i) {
    precise vec3 p = x + R * uProbeDirs[i];
    float D = densityAtPoint(p);
    if (D == 0.0) continue;  // its term is 0: not traced (as on the CPU)
    vec3 Sp = sourceTowardsEye(p);
    precise vec3 d = p - x;
    precise vec3 taylor = S + d.x * dS0 + d.y * dS1 + d.z * dS2;
#ifdef SL_BOUNDED
    taylor = clamp(taylor, vec3(uTaylorBounds.x), vec3(uTaylorBounds.y));
#endif
#ifdef SL_LOG_SPACE
    // ln V held: compared on V, what the image sees (localShadingError's ErrorSpace::log).
    precise vec3 diff = abs(exp(taylor) - exp(Sp));
#else
    precise vec3 diff = abs(taylor - Sp);
#endif
#ifdef SL_WEIGHT_A
    diff *= lightFactorTowardsEye(p);  // the error of S = A ⊙ V (ErrorSpace::weightA)
#endif
    sum += (diff.x + diff.y + diff.z) / 3.0 * D;
  }
  probeSums[j * gl_NumWorkGroups.y + uint(g)] = sum;
}
