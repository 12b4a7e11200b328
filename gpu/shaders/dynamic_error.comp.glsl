// Dynamic sampling (paper Sec. 5), four passes per level, none of which has an invocation trace
// more than a few lights for one point (one invocation per sample traced up to 47 points × every
// light: 2 240 invocations for 64 lights, 348 ms on an H200; and llvmpipe ends every loop of an
// invocation after 65535 iterations in all, which 40 probes × 16 lights reached):
// 0. volume_tracer.comp.glsl (gpu::traceLevel), parallel over (sample, point, light): S and ∇S
//    of the level's samples into results[];
// 1. this file without SL_COMBINE, for a level that may split (a final level stops after
//    pass 0): τ to the viewer (kept in errors[j] until pass 3) and on level 0 the sample's
//    contribution R³·mean|S|·D·τ (the scale of a relative ε; with SL_WEIGHT_A |S| times A at
//    the sample). With tau "visible" (SL_TAU_LANES 8) a workgroup holds 8 samples × 8 lanes:
//    lane 0 traces the sample's own τ (or reads its ancestor's), lanes 1–6 the six axis probes',
//    and lane 0 takes their maximum in the serial order — one trace per invocation instead of
//    seven in series; otherwise (SL_TAU_LANES 1) one invocation per sample;
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
#ifdef SL_COMBINE
layout(local_size_x = 64) in;
#else
#ifndef SL_TAU_LANES
#define SL_TAU_LANES 1
#endif
const uint kLanes = uint(SL_TAU_LANES);  // 8 with tau "visible", else 1
const uint kSlots = 64u / kLanes;        // samples per workgroup
layout(local_size_x = SL_TAU_LANES, local_size_y = 64 / SL_TAU_LANES) in;
#endif

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
#ifdef SL_ERROR_BIAS
uniform float uBiasWeight;      // bias_weight k: the groups' sums come in pairs (|·|, signed)
#endif

void main() {
  uint j = SL_LINEAR_INVOCATION;
  if (j >= counts[uLevel]) return;
  float R = samples[j].w;
  precise float sum = 0.0;
#ifdef SL_ERROR_BIAS
  precise float bias = 0.0;
  for (int g = 0; g < uProbeGroups; ++g) {
    sum += probeSums[2u * (j * uint(uProbeGroups) + uint(g))];
    bias += probeSums[2u * (j * uint(uProbeGroups) + uint(g)) + 1u];
  }
  sum += uBiasWeight * abs(bias);
#else
  for (int g = 0; g < uProbeGroups; ++g) sum += probeSums[j * uint(uProbeGroups) + uint(g)];
#endif
  precise float E = R * R * R * sum / float(uProbes) * errors[j];  // errors[j]: τ of pass 1
  errors[j] = E;
}
#else
uniform int uTauMode;           // 0: level 0 (trace τ, store it in rootTau), 1: ancestor's, 2: own
uniform float uTauDelta1;       // step of the τ trace
uniform vec3 uProbeDirs[40];    // probeOffsets() of the CPU (the six axis probes of tau "visible")

float viewTransmittance(vec3 x) { return exp(-uSigmaT * opticalDepth(x, uEye, uTauDelta1)); }

shared float sTau[64];  // [slot · kLanes + lane]: τ of the sample (lane 0) and its probes

// The sample j's E-pass values once its lanes' τ are in sTau (lane 0 only).
void finish(uint j, uint count, uint slot) {
  vec4 pr = samples[j];
  vec3 x = pr.xyz;
  float R = pr.w;
  float tau = sTau[slot * kLanes];
  if (uTauMode == 0) rootTau[j] = tau;
#if SL_TAU_LANES > 1
  // tau "visible": the most visible of the sample and its six axis probes (the CPU's
  // probePoints order; rootTau keeps the centre's τ).
  for (uint i = 1u; i <= 6u; ++i) tau = max(tau, sTau[slot * kLanes + i]);
#endif
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

// Workgroups stride over the level's samples (the dispatch covers its capacity; the count is
// known only here), kSlots samples at a time; the loop is uniform over the workgroup, so its
// barriers are too.
void main() {
  uint count = counts[uLevel];
  uint lane = gl_LocalInvocationID.x, slot = gl_LocalInvocationID.y;
  // Workgroups stride over the samples; after level 0 without tau "visible" the count pass's
  // dispatch may span two axes (linearDispatch).
  const uint groupCount = gl_NumWorkGroups.x * gl_NumWorkGroups.y;
  for (uint base = SL_LINEAR_GROUP * kSlots; base < count; base += groupCount * kSlots) {
    uint j = base + slot;
    if (j < count && lane <= 6u) {
      vec4 pr = samples[j];
      float t;
      if (lane == 0u) {
        t = uTauMode == 1 ? rootTau[ancestors[j]] : viewTransmittance(pr.xyz);
      } else {
        precise vec3 p = pr.xyz + pr.w * uProbeDirs[lane - 1u];
        t = viewTransmittance(p);
      }
      sTau[slot * kLanes + lane] = t;
    }
    memoryBarrierShared();
    barrier();
    if (j < count && lane == 0u) finish(j, count, slot);
    memoryBarrierShared();
    barrier();  // sTau is rewritten by the next round
  }
}
#endif
