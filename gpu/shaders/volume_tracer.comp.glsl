// Radiance evaluator (paper Sec. 4): S and, with SL_GRADIENTS, the central-difference gradient
// (step uDelta2) of every sample, parallel over (sample, point, light): a workgroup holds
// SL_SLOTS samples (z); each sample's SL_ROWS points (y: the sample, then x ± δ2·e_a for
// a = 0, 1, 2) are traced by SL_LANES lanes (x) that split the lights (lane k: lights k,
// k + SL_LANES, …) and add their parts in shared memory, in a fixed tree order. The sums are
// those of sourceTowardsEye (common.glsl) up to their order. Workgroups stride over the samples
// (a dispatch stays within the device's workgroup count whatever uCount is).
#ifndef SL_LANES  // set by gpu::VolumeTracerGpu (tracerShape); these are for a lone compile
#define SL_LANES 1
#define SL_ROWS 7
#define SL_SLOTS 32
#endif
layout(local_size_x = SL_LANES, local_size_y = SL_ROWS, local_size_z = SL_SLOTS) in;

layout(std430, binding = BINDING_SAMPLES) readonly buffer Positions { vec4 positions[]; };  // xyz
layout(std430, binding = BINDING_RADIANCE) writeonly buffer Results { RadianceRecord results[]; };
#ifdef SL_LEVEL_COUNT
// Dynamic sampling's level uLevel (gpu::traceLevel): its count is written on the GPU.
layout(std430, binding = BINDING_LEVEL_COUNTS) readonly buffer LevelCounts { uint counts[]; };
uniform uint uLevel;
#else
uniform uint uCount;
#endif
uniform float uDelta2;

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

// Point `row` of the sample at p: p, then p + δ2·e_a and p − δ2·e_a for a = 0, 1, 2.
vec3 rowPoint(vec3 p, uint row) {
  if (row == 0u) return p;
  vec3 e = vec3(0.0);
  e[(row - 1u) / 2u] = uDelta2;
  return (row & 1u) == 1u ? p + e : p - e;
}

void main() {
  const uint lane = gl_LocalInvocationID.x, row = gl_LocalInvocationID.y;
  const uint slot = gl_LocalInvocationID.z;
  const uint stride = gl_NumWorkGroups.x * uint(SL_SLOTS);
#ifdef SL_LEVEL_COUNT
  const uint count = counts[uLevel];
#else
  const uint count = uCount;
#endif
  // The loop's bounds are the workgroup's: every barrier is reached by all its invocations.
  for (uint base = gl_WorkGroupID.x * uint(SL_SLOTS); base < count; base += stride) {
    const uint i = base + slot;
    const bool live = i < count;
    const vec3 q = rowPoint(live ? positions[i].xyz : vec3(0.0), row);
    const vec3 toViewer = towardsEye(q);
    vec3 s = vec3(0.0), a = vec3(0.0);
    float outside = 0.0;
    if (live) {
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
#ifdef SL_FACTOR_LIGHTS
      needsFree[slot][row] =
          live && factoredNeedsFree(partA[slot][row][0].rgb, partS[slot][row][0].w);
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
    // value[] is read above before the next sample's lanes write partS (no barrier needed:
    // value is written again only after two more barriers).
  }
}
