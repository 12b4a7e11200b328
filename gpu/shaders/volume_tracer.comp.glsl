// Radiance evaluator (paper Sec. 4): S and, with SL_GRADIENTS, the central-difference gradient
// (step uDelta2) of every sample, parallel over (sample, point, light): a workgroup holds
// SL_SLOTS samples (z); each sample's SL_ROWS points (y: the sample, then x ± δ2·e_a for
// a = 0, 1, 2) are traced by SL_LANES lanes (x) that split the lights (lane k: lights k,
// k + SL_LANES, …) and add their parts in shared memory, in a fixed tree order. The sums are
// those of sourceTowardsEye (common.glsl) up to their order. Workgroups stride over the samples
// (a dispatch stays within the device's workgroup count whatever uCount is).
// SL_PROBES: dynamic sampling's probe pass (gpu/dynamic_sampling.cpp; after pass 1 of
// dynamic_error.comp.glsl): the rows are the kProbeGroup probes x_i = x_j + R_j·d_i of group
// g = the workgroup's y; the traced S at each (0 where D = 0: not traced, as on the CPU) against
// the sample's Taylor estimate L̃ (S and ∇S in results[]) gives mean_RGB|L̃ − L|·D (with
// SL_WEIGHT_A times A at the probe per channel; SL_LOG_SPACE compares V = exp), and lane 0 of
// row 0 sums the group's terms in probe order, as localShadingError (sampling/
// dynamic_sampling.cpp) sums each group, into probeSums[j·groups + g].
#ifndef SL_LANES  // set by gpu::VolumeTracerGpu (tracerShape); these are for a lone compile
#define SL_LANES 1
#define SL_ROWS 7
#define SL_SLOTS 32
#endif
layout(local_size_x = SL_LANES, local_size_y = SL_ROWS, local_size_z = SL_SLOTS) in;

layout(std430, binding = BINDING_SAMPLES) readonly buffer Positions { vec4 positions[]; };  // xyz, R
#ifdef SL_PROBES
layout(std430, binding = BINDING_RADIANCE) readonly buffer Results { RadianceRecord results[]; };
layout(std430, binding = BINDING_PROBE_SUMS) writeonly buffer ProbeSums { float probeSums[]; };
uniform int uProbes;            // 6, 14, 26 or 40
uniform vec3 uProbeDirs[40];    // probeOffsets() of the CPU
#ifdef SL_BOUNDED
uniform vec2 uTaylorBounds;     // TaylorBounds (lo, hi): the Taylor estimate is clamped to it
#endif
shared float term[SL_SLOTS][SL_ROWS];
#ifdef SL_ERROR_BIAS
// bias_weight > 0: each group's sum of mean_RGB(L̃ − L)·D (signed; with SL_WEIGHT_A times A) too,
// at probeSums[2·(sample's group index) + 1], its sum of |·| at [2·… + 0].
shared float termBias[SL_SLOTS][SL_ROWS];
#endif
#else
layout(std430, binding = BINDING_RADIANCE) writeonly buffer Results { RadianceRecord results[]; };
uniform float uDelta2;
#ifdef SL_LIT_REACH
uniform float uReach;  // TracerSteps::reach: the radiance voxel's half-diagonal
#endif
#endif
#if defined(SL_LEVEL_COUNT) || defined(SL_PROBES)
// Dynamic sampling's level uLevel (gpu::traceLevel): its count is written on the GPU; with
// SL_LEVEL_COUNT the samples from counts[uFirstSlot] on (0xffffffff: from 0), the top-up's
// children at the end of the final list.
layout(std430, binding = BINDING_LEVEL_COUNTS) readonly buffer LevelCounts { uint counts[]; };
uniform uint uLevel;
#ifdef SL_LEVEL_COUNT
uniform uint uFirstSlot;
#endif
#else
uniform uint uCount;
#endif

// Per (slot, row, lane): rgb a part of S (or s), w the lights outside their cone; rgb a part of
// A (factored). Lane 0 ends with the sums over every light.
shared vec4 partS[SL_SLOTS][SL_ROWS][SL_LANES];
shared vec4 partA[SL_SLOTS][SL_ROWS][SL_LANES];
shared vec4 totalS[SL_SLOTS][SL_ROWS];
shared vec4 totalA[SL_SLOTS][SL_ROWS];
shared bool needsFree[SL_SLOTS][SL_ROWS];
shared vec3 value[SL_SLOTS][SL_ROWS];

// Adds the lanes' parts into lane 0 (every invocation of the workgroup calls it).
void reduceLanes(uint slot, uint row, uint lane) {
  for (uint stride = uint(SL_LANES) / 2u; stride > 0u; stride >>= 1u) {
    memoryBarrierShared();
    barrier();
    if (lane < stride) {
      partS[slot][row][lane] += partS[slot][row][lane + stride];
      partA[slot][row][lane] += partA[slot][row][lane + stride];
    }
  }
  memoryBarrierShared();
  barrier();
}

#ifndef SL_PROBES
// Point `row` of the sample at p: p, then p + δ2·e_a and p − δ2·e_a for a = 0, 1, 2.
vec3 rowPoint(vec3 p, uint row) {
  if (row == 0u) return p;
  vec3 e = vec3(0.0);
  e[(row - 1u) / 2u] = uDelta2;
  return (row & 1u) == 1u ? p + e : p - e;
}
#endif

void main() {
  const uint lane = gl_LocalInvocationID.x, row = gl_LocalInvocationID.y;
  const uint slot = gl_LocalInvocationID.z;
  const uint stride = gl_NumWorkGroups.x * uint(SL_SLOTS);
#if defined(SL_LEVEL_COUNT) || defined(SL_PROBES)
  const uint count = counts[uLevel];
#else
  const uint count = uCount;
#endif
#ifdef SL_LEVEL_COUNT
  const uint first = uFirstSlot == 0xffffffffu ? 0u : counts[uFirstSlot];
#else
  const uint first = 0u;
#endif
  // The loop's bounds are the workgroup's: every barrier is reached by all its invocations.
  for (uint base = first + gl_WorkGroupID.x * uint(SL_SLOTS); base < count; base += stride) {
    const uint i = base + slot;
    const bool live = i < count;
#ifdef SL_PROBES
    const int probe = int(gl_WorkGroupID.y) * SL_ROWS + int(row);
    const vec4 pr = live ? positions[i] : vec4(0.0);
    precise vec3 q = pr.xyz + pr.w * uProbeDirs[min(probe, uProbes - 1)];
    const float D = live && probe < uProbes ? densityAtPoint(q) : 0.0;
    const bool traced = D != 0.0;  // a term of 0 is not traced (as on the CPU)
#else
    const vec3 q = rowPoint(live ? positions[i].xyz : vec3(0.0), row);
#ifdef SL_LIT_REACH
    // TracerSteps::reach: a sample no spot cone reaches within R + uReach is not traced (V = 0,
    // ln V = ln SL_MIN_V, ∇ = 0); a point of radius 0 always is.
    const bool traced = live && (!(positions[i].w > 0.0) ||
                                 litReaches(positions[i].xyz, positions[i].w + uReach));
#else
    const bool traced = live;
#endif
#endif
    const vec3 toViewer = towardsEye(q);
    vec3 s = vec3(0.0), a = vec3(0.0);
    float outside = 0.0;
    if (traced) {
#ifdef SL_FACTOR_LIGHTS
      factoredPart(q, toViewer, int(lane), SL_LANES, s, a, outside);
#else
      s = sourceRadiancePart(q, toViewer, int(lane), SL_LANES);
#endif
    }
    partS[slot][row][lane] = vec4(s, outside);
    partA[slot][row][lane] = vec4(a, 0.0);
    reduceLanes(slot, row, lane);
    if (lane == 0u) {
      totalS[slot][row] = partS[slot][row][0];
      totalA[slot][row] = partA[slot][row][0];
#if defined(SL_PROBES) && defined(SL_WEIGHT_A)
      // A probe's term is weighted by A: the channels where A is zero (what the cones-ignored
      // sums fill) count for nothing, so they are not traced (the CPU skips such probes).
      needsFree[slot][row] = false;
#elif defined(SL_FACTOR_LIGHTS)
      needsFree[slot][row] =
          traced && factoredNeedsFree(partA[slot][row][0].rgb, partS[slot][row][0].w);
#else
      needsFree[slot][row] = false;
#endif
    }
    memoryBarrierShared();
    barrier();
    // The cones-ignored sums, only where a channel of A is zero (rare: outside every cone).
    vec3 sf = vec3(0.0), af = vec3(0.0);
#ifdef SL_FACTOR_LIGHTS
    if (needsFree[slot][row]) factoredFreePart(q, toViewer, int(lane), SL_LANES, sf, af);
#endif
    partS[slot][row][lane] = vec4(sf, 0.0);
    partA[slot][row][lane] = vec4(af, 0.0);
    reduceLanes(slot, row, lane);
    if (lane == 0u) {
#if defined(SL_FACTOR_LIGHTS)
      vec3 v = factoredCombine(totalS[slot][row].rgb, totalA[slot][row].rgb,
                               partS[slot][row][0].rgb, partA[slot][row][0].rgb);
#if defined(SL_LOG_SPACE)
      v = log(max(v, vec3(SL_MIN_V)));
#endif
#else
      vec3 v = totalS[slot][row].rgb;
#endif
      value[slot][row] = v;
    }
    memoryBarrierShared();
    barrier();
#ifdef SL_PROBES
    if (lane == 0u) {
      float t = 0.0, b = 0.0;
      if (traced) {
        const vec3 Sp = value[slot][row];
        const vec3 S = results[i].S.xyz;
        precise vec3 d = q - pr.xyz;
        precise vec3 taylor =
            S + d.x * results[i].dS[0].xyz + d.y * results[i].dS[1].xyz + d.z * results[i].dS[2].xyz;
#ifdef SL_BOUNDED
        taylor = clamp(taylor, vec3(uTaylorBounds.x), vec3(uTaylorBounds.y));
#endif
#ifdef SL_LOG_SPACE
        // ln V held: compared on V, what the image sees (localShadingError's ErrorSpace::log).
        precise vec3 signedDiff = exp(taylor) - exp(Sp);
#else
        precise vec3 signedDiff = taylor - Sp;
#endif
        precise vec3 diff = abs(signedDiff);
#ifdef SL_WEIGHT_A
        const vec3 A = lightFactorTowardsEye(q);  // the error of S = A ⊙ V (ErrorSpace::weightA)
        diff *= A;
        signedDiff *= A;
#endif
        t = (diff.x + diff.y + diff.z) / 3.0 * D;
        b = (signedDiff.x + signedDiff.y + signedDiff.z) / 3.0 * D;
      }
      term[slot][row] = t;
#ifdef SL_ERROR_BIAS
      termBias[slot][row] = b;
#endif
    }
    memoryBarrierShared();
    barrier();
    if (live && lane == 0u && row == 0u) {
      // The group's terms in probe order (a term of 0 adds nothing: the CPU skips it).
      precise float sum = 0.0;
      for (int r = 0; r < SL_ROWS; ++r) sum += term[slot][r];
#ifdef SL_ERROR_BIAS
      precise float bias = 0.0;
      for (int r = 0; r < SL_ROWS; ++r) bias += termBias[slot][r];
      probeSums[2u * (i * gl_NumWorkGroups.y + gl_WorkGroupID.y)] = sum;
      probeSums[2u * (i * gl_NumWorkGroups.y + gl_WorkGroupID.y) + 1u] = bias;
#else
      probeSums[i * gl_NumWorkGroups.y + gl_WorkGroupID.y] = sum;
#endif
    }
#else
    if (live && lane == 0u && row == 0u) {
      results[i].S = vec4(value[slot][0], 0.0);
#ifdef SL_GRADIENTS
      for (uint d = 0u; d < 3u; ++d)
        results[i].dS[d] =
            vec4((value[slot][1u + 2u * d] - value[slot][2u + 2u * d]) / (2.0 * uDelta2), 0.0);
#else
      for (uint d = 0u; d < 3u; ++d) results[i].dS[d] = vec4(0.0);
#endif
    }
#endif
    // value[] is read above before the next sample's lanes write partS (no barrier needed:
    // value is written again only after two more barriers).
  }
}
