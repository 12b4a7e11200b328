// Dynamic sampling (paper Sec. 5), four passes per level, none of which has an invocation trace
// more than a few lights for one point (one invocation per sample traced up to 47 points × every
// light: 2 240 invocations for 64 lights, 348 ms on an H200; and llvmpipe ends every loop of an
// invocation after 65535 iterations in all, which 40 probes × 16 lights reached):
// 0. volume_tracer.comp.glsl (gpu::traceLevel), parallel over (sample, point, light): S and ∇S
//    of the level's samples into results[];
// 1. this file without SL_COMBINE, one invocation per sample of a level that may split (a
//    final level stops after pass 0): τ to the viewer (kept in errors[j] until pass 3) and on
//    level 0 the sample's contribution R³·mean|S|·D·τ (the scale of a relative ε; with
//    SL_WEIGHT_A |S| times A at the sample);
// 2. volume_tracer.comp.glsl with SL_PROBES, parallel over (sample, probe, light): each group of
//    kProbeGroup probes' sum of mean_RGB|L̃ − L|·D (with SL_WEIGHT_A mean_RGB(A ⊙ |L̃ − L|)·D, A
//    at the probe);
// 3. this file with SL_COMBINE, one invocation per sample: E_j = R³·(Σ of the groups' sums in
//    group order)/n·τ, Eq. 5.
// The level's sample count is read from the GPU (counts[uLevel], written by the count pass of
// dynamic_level.comp.glsl; the dispatches are indirect or stride over the samples); the
// threshold and the split decisions are left to the next passes. Mirrors
// sampling/dynamic_sampling.cpp (localShadingError, which sums the probes in the same groups,
// sampleContribution, viewTransmittance) operation for operation, but for the order in which
// the lights' terms of one point are added (the lanes' tree).
layout(local_size_x = 64) in;

layout(std430, binding = BINDING_SAMPLES) readonly buffer Samples { vec4 samples[]; };  // xyz, valid radius
layout(std430, binding = BINDING_ANCESTORS) readonly buffer Ancestors { int ancestors[]; };
layout(std430, binding = BINDING_ROOT_TAU) buffer RootTau { float rootTau[]; };  // τ of every level-0 sample
layout(std430, binding = BINDING_RADIANCE) readonly buffer Results { RadianceRecord results[]; };
// Pass 1 leaves τ at [j] and on level 0 the contribution at [count + j]; pass 3 replaces τ by E_j.
layout(std430, binding = BINDING_ERRORS) buffer Errors { float errors[]; };
// The level counts.
layout(std430, binding = BINDING_LEVEL_COUNTS) readonly buffer LevelCounts { uint counts[]; };

uniform uint uLevel;            // k: the level's sample count is counts[k]

#ifdef SL_COMBINE
layout(std430, binding = BINDING_PROBE_SUMS) readonly buffer ProbeSums { float probeSums[]; };
uniform int uProbes;            // 6, 14, 26 or 40
uniform int uProbeGroups;       // ceil(uProbes / kProbeGroup): sums per sample

void main() {
  uint j = gl_GlobalInvocationID.x;
  if (j >= counts[uLevel]) return;
  float R = samples[j].w;
  precise float sum = 0.0;
  for (int g = 0; g < uProbeGroups; ++g) sum += probeSums[j * uint(uProbeGroups) + uint(g)];
  precise float E = R * R * R * sum / float(uProbes) * errors[j];  // errors[j]: τ of pass 1
  errors[j] = E;
}
#else
uniform int uTauMode;           // 0: level 0 (trace τ, store it in rootTau), 1: ancestor's, 2: own
uniform float uTauDelta1;       // step of the τ trace
uniform int uVisibleTau;        // 1: τ = max(τ, τ at the six axis probes) (tau "visible")
uniform vec3 uProbeDirs[40];    // probeOffsets() of the CPU (the six axis probes of uVisibleTau)

float viewTransmittance(vec3 x) { return exp(-uSigmaT * opticalDepth(x, uEye, uTauDelta1)); }

void main() {
  uint j = gl_GlobalInvocationID.x;
  uint count = counts[uLevel];
  if (j >= count) return;
  vec4 pr = samples[j];
  vec3 x = pr.xyz;
  float R = pr.w;
  float tau;
  if (uTauMode == 0) {
    tau = viewTransmittance(x);
    rootTau[j] = tau;
  } else if (uTauMode == 1) {
    tau = rootTau[ancestors[j]];
  } else {
    tau = viewTransmittance(x);
  }
  if (uVisibleTau != 0) {
    // tau "visible": the most visible of the sample and its six axis probes (the CPU's
    // probePoints order; rootTau keeps the centre's τ).
    for (int i = 0; i < 6; ++i) {
      precise vec3 p = x + R * uProbeDirs[i];
      tau = max(tau, viewTransmittance(p));
    }
  }
  errors[j] = tau;  // E_j once pass 3 has combined the probe groups
  if (uTauMode == 0) {
    vec3 S = results[j].S.rgb;  // pass 0's
#ifdef SL_LOG_SPACE
    precise vec3 a = exp(S);
#else
    precise vec3 a = abs(S);
#endif
#ifdef SL_WEIGHT_A
    a *= lightFactorTowardsEye(x);  // S = A ⊙ V (ErrorSpace::weightA)
#endif
    precise float c = R * R * R * ((a.x + a.y + a.z) / 3.0) * densityAtPoint(x) * tau;
    errors[count + j] = c;
  }
}
#endif
