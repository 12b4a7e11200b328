// Dynamic sampling's final sample list, assembled on the GPU in the CPU's order (the samples
// each level keeps, level by level in index order, then the budget's top-up children, level by
// level in ascending vertex order: scatterlab::dynamicSampling and applyTopUp), so that a
// resident frame gathers it where it lies. The list's parts lie one after the other in one flags
// buffer (part p from uBase): a flags pass per part, ONE exclusive scan over all of them
// (gpu/scan.h), whose offsets are the list's slots, a scatter per part, then SL_PART_ENDS.
// SL_KEEP_FLAGS: one invocation per sample slot of level k: 1 when the sample stays. With
// uKeepAll (the final level, and a level split into the per-voxel fallback's grid, where a split
// keeps its sample) every sample of the level stays; else it stays unless it split (E >
// threshold; with a budget, of a group at or above the lower of the level's cut and the
// top-up's).
// SL_CHILD_FLAGS: one invocation per vertex of G_{k+1}: 1 for a top-up child (no split of the
// pass marked it, and its worst marking candidate's group is topped up).
// SL_KEEP_SCATTER / SL_CHILD_SCATTER: the flagged samples (position, radius, S and ∇S) or
// children (the vertex, the grid's radius; S by the tracer afterwards) into the list.
// SL_PART_ENDS (one invocation): each part's total, and the list's ends after the kept samples,
// after the children with ∇S and after all; an end past the list's capacity is recorded as an
// overflow (the samples past it are dropped); the children's tracer dispatches.
#ifdef SL_PART_ENDS
layout(local_size_x = 1) in;
#else
layout(local_size_x = 256) in;
#endif

// common.glsl's RadianceRecord (S, ∇S), copied whole.
struct Record {
  vec4 S;
  vec4 dS[3];
};

// Only SL_PART_ENDS writes counts; the flags passes only write flags, the others only read them.
#if defined(SL_KEEP_FLAGS) || defined(SL_CHILD_FLAGS) || defined(SL_KEEP_SCATTER) || \
    defined(SL_CHILD_SCATTER)
layout(std430, binding = BINDING_LEVEL_COUNTS) readonly buffer LevelCounts { uint counts[]; };
#else
layout(std430, binding = BINDING_LEVEL_COUNTS) buffer LevelCounts { uint counts[]; };
#endif
#if defined(SL_KEEP_FLAGS) || defined(SL_CHILD_FLAGS)
layout(std430, binding = BINDING_IN_SET) writeonly buffer Flags { uint flags[]; };
#else
layout(std430, binding = BINDING_IN_SET) readonly buffer Flags { uint flags[]; };
#endif
layout(std430, binding = BINDING_OFFSETS) readonly buffer Offsets { uint offsets[]; };
uniform uint uCapacity;   // the list's capacity
#ifndef SL_PART_ENDS
uniform uint uCount;      // invocations: the level's capacity, or G_{k+1}'s vertices
uniform uint uBase;       // the part's first flag
#endif

#if defined(SL_KEEP_FLAGS)
layout(std430, binding = BINDING_ERRORS) readonly buffer Errors { float errors[]; };
layout(std430, binding = BINDING_THRESHOLD) readonly buffer Threshold { double errorScale; double threshold; };
uniform uint uLevel;      // k: its count is counts[k]
uniform int uBudget;      // 1: split by the cuts
uniform uint uCutSlot;    // counts[slot]: the level's cut
uniform uint uTopCutSlot; // counts[slot]: the top-up's cut
uniform int uKeepAll;     // 1: every sample of the level stays
void main() {
  uint j = SL_LINEAR_INVOCATION;
  if (j >= uCount) return;
  uint stays = 0u;
  if (j < counts[uLevel]) {
    stays = 1u;
    if (uKeepAll == 0 && double(errors[j]) > threshold) {
      stays = 0u;
      if (uBudget != 0) {
        int lowest = int(min(counts[uCutSlot], counts[uTopCutSlot]));
        stays = errorGroup(errors[j], threshold) < lowest ? 1u : 0u;
      }
    }
  }
  flags[uBase + j] = stays;
}
#elif defined(SL_CHILD_FLAGS)
layout(std430, binding = BINDING_VERTEX_KEYS) readonly buffer VertexKeys { uint vertexKeys[]; };
uniform uint uCutSlot;    // counts[slot]: the level's cut
uniform uint uTopCutSlot; // counts[slot]: the top-up's cut
void main() {
  uint v = SL_LINEAR_INVOCATION;
  if (v >= uCount) return;
  uint key = vertexKeys[v];
  flags[uBase + v] =
      key > 0u && key - 1u >= counts[uTopCutSlot] && key - 1u < counts[uCutSlot] ? 1u : 0u;
}
#elif defined(SL_KEEP_SCATTER)
layout(std430, binding = BINDING_SAMPLES) readonly buffer Samples { vec4 samples[]; };
layout(std430, binding = BINDING_RADIANCE) readonly buffer Radiance { Record radiance[]; };
layout(std430, binding = BINDING_NEXT_SAMPLES) writeonly buffer Final { vec4 finalSamples[]; };
layout(std430, binding = BINDING_NEXT_RADIANCE) writeonly buffer FinalRadiance { Record finalRadiance[]; };
void main() {
  uint j = SL_LINEAR_INVOCATION;
  if (j >= uCount || flags[uBase + j] == 0u) return;
  uint dst = offsets[uBase + j];
  if (dst >= uCapacity) return;
  finalSamples[dst] = samples[j];
  finalRadiance[dst] = radiance[j];
}
#elif defined(SL_CHILD_SCATTER)
// gridVertex: grid_vertex.glsl, prepended.
layout(std430, binding = BINDING_NEXT_SAMPLES) writeonly buffer Final { vec4 finalSamples[]; };
uniform float uRadius;
void main() {
  uint v = SL_LINEAR_INVOCATION;
  if (v >= uCount || flags[uBase + v] == 0u) return;
  uint dst = offsets[uBase + v];
  if (dst >= uCapacity) return;
  finalSamples[dst] = vec4(gridVertex(v), uRadius);
}
#else  // SL_PART_ENDS
// Per part: its first flag, its flags, the counts slot that receives its total, and which ends
// it comes before: 0 a level's kept samples, 1 children with ∇S, 2 the fallback's children.
layout(std430, binding = BINDING_ASSEMBLE_PARTS) readonly buffer Parts { uvec4 parts[]; };
uniform uint uParts;
uniform uint uKeptEndSlot;   // counts[slot]: the end of the kept samples
uniform uint uGradEndSlot;   // counts[slot]: the end of the children with ∇S
uniform uint uEndSlot;       // counts[slot]: the list's end
uniform uint uOverflowSlot;  // counts[slot]: the end asked beyond the capacity
uniform uint uChildTraceSlot;   // counts[slot + 3·batch ...]: the tracer's (x, 1, 1) for the
                                // children with ∇S (batch 0) and the voxels' (batch 1)
uniform uint uSamplesPerGroup;  // samples a tracer workgroup holds
uniform uint uMaxTraceGroups;
void main() {
  uint end = 0u;
  uint group = 0u;
  for (uint p = 0u; p < uParts; ++p) {
    uvec4 part = parts[p];
    for (; group < part.w; ++group) counts[group == 0u ? uKeptEndSlot : uGradEndSlot] = min(end, uCapacity);
    uint last = part.x + part.y - 1u;
    uint total = part.y == 0u ? 0u : offsets[last] + (flags[last] != 0u ? 1u : 0u) - offsets[part.x];
    counts[part.z] = total;
    end += total;
  }
  for (; group < 2u; ++group) counts[group == 0u ? uKeptEndSlot : uGradEndSlot] = min(end, uCapacity);
  counts[uEndSlot] = min(end, uCapacity);
  counts[uOverflowSlot] = end > uCapacity ? end : 0u;
  // The children's tracer passes, for their own counts (the batches end where the next begins).
  uint from[2] = uint[2](counts[uKeptEndSlot], counts[uGradEndSlot]);
  uint to[2] = uint[2](counts[uGradEndSlot], counts[uEndSlot]);
  for (uint b = 0u; b < 2u; ++b) {
    uint n = to[b] - from[b];
    counts[uChildTraceSlot + 3u * b] = min((n + uSamplesPerGroup - 1u) / uSamplesPerGroup, uMaxTraceGroups);
    counts[uChildTraceSlot + 3u * b + 1u] = 1u;
    counts[uChildTraceSlot + 3u * b + 2u] = 1u;
  }
}
#endif
