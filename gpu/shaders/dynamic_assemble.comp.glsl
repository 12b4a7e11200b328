// Dynamic sampling's final sample list, assembled on the GPU in the CPU's order (the samples
// each level keeps, level by level in index order, then the budget's top-up children, level by
// level in ascending vertex order: scatterlab::dynamicSampling and applyTopUp), so that a
// resident frame gathers it where it lies. Each part: flags, an exclusive scan
// (gpu/scan.h), a scatter at the list's running end, then SL_ADVANCE moves the end.
// SL_KEEP_FLAGS: one invocation per sample slot of a split level k: 1 when the sample stays,
// unless it split (E > threshold; with a budget, of a group at or above the lower of the level's
// cut and the top-up's). (The final level, and a level split into the per-voxel fallback's grid,
// where a split keeps its sample, keep all: SL_KEEP_COPY.)
// SL_CHILD_FLAGS: one invocation per vertex of G_{k+1}: 1 for a top-up child (no split of the
// pass marked it, and its worst marking candidate's group is topped up).
// SL_KEEP_COPY: a level that keeps all its samples, copied without flags.
// SL_KEEP_SCATTER / SL_CHILD_SCATTER: the flagged samples (position, radius, S and ∇S) or
// children (the vertex, the grid's radius; S by the tracer afterwards) into the list.
// SL_ADVANCE (one invocation): the part's total moves the list's end; an end past the list's
// capacity is recorded as an overflow (the samples past it are dropped).
#ifdef SL_ADVANCE
layout(local_size_x = 1) in;
#else
layout(local_size_x = 256) in;
#endif

// common.glsl's RadianceRecord (S, ∇S), copied whole.
struct Record {
  vec4 S;
  vec4 dS[3];
};

layout(std430, binding = BINDING_LEVEL_COUNTS) buffer LevelCounts { uint counts[]; };
layout(std430, binding = BINDING_IN_SET) buffer Flags { uint flags[]; };
layout(std430, binding = BINDING_OFFSETS) readonly buffer Offsets { uint offsets[]; };
uniform uint uCount;      // invocations: the level's capacity, or G_{k+1}'s vertices
uniform uint uEndSlot;    // counts[slot]: the list's end (its count so far)
uniform uint uCapacity;   // the list's capacity

#if defined(SL_KEEP_FLAGS)
layout(std430, binding = BINDING_ERRORS) readonly buffer Errors { float errors[]; };
layout(std430, binding = BINDING_THRESHOLD) readonly buffer Threshold { double errorScale; double threshold; };
uniform uint uLevel;      // k: its count is counts[k]
uniform int uBudget;      // 1: split by the cuts
uniform uint uCutSlot;    // counts[slot]: the level's cut
uniform uint uTopCutSlot; // counts[slot]: the top-up's cut
void main() {
  uint j = gl_GlobalInvocationID.x;
  if (j >= uCount) return;
  uint stays = 0u;
  if (j < counts[uLevel]) {
    stays = 1u;
    if (double(errors[j]) > threshold) {
      stays = 0u;
      if (uBudget != 0) {
        int lowest = int(min(counts[uCutSlot], counts[uTopCutSlot]));
        stays = errorGroup(errors[j], threshold) < lowest ? 1u : 0u;
      }
    }
  }
  flags[j] = stays;
}
#elif defined(SL_CHILD_FLAGS)
layout(std430, binding = BINDING_VERTEX_KEYS) readonly buffer VertexKeys { uint vertexKeys[]; };
uniform uint uCutSlot;    // counts[slot]: the level's cut
uniform uint uTopCutSlot; // counts[slot]: the top-up's cut
void main() {
  uint v = gl_GlobalInvocationID.x;
  if (v >= uCount) return;
  uint key = vertexKeys[v];
  flags[v] = key > 0u && key - 1u >= counts[uTopCutSlot] && key - 1u < counts[uCutSlot] ? 1u : 0u;
}
#elif defined(SL_KEEP_SCATTER)
layout(std430, binding = BINDING_SAMPLES) readonly buffer Samples { vec4 samples[]; };
layout(std430, binding = BINDING_RADIANCE) readonly buffer Radiance { Record radiance[]; };
layout(std430, binding = BINDING_NEXT_SAMPLES) writeonly buffer Final { vec4 finalSamples[]; };
layout(std430, binding = BINDING_NEXT_RADIANCE) writeonly buffer FinalRadiance { Record finalRadiance[]; };
void main() {
  uint j = gl_GlobalInvocationID.x;
  if (j >= uCount || flags[j] == 0u) return;
  uint dst = counts[uEndSlot] + offsets[j];
  if (dst >= uCapacity) return;
  finalSamples[dst] = samples[j];
  finalRadiance[dst] = radiance[j];
}
#elif defined(SL_KEEP_COPY)
// A level that keeps every sample (the final level; one split into the fallback's grid): its
// first counts[uLevel] samples copied in order, no flags or scan.
layout(std430, binding = BINDING_SAMPLES) readonly buffer Samples { vec4 samples[]; };
layout(std430, binding = BINDING_RADIANCE) readonly buffer Radiance { Record radiance[]; };
layout(std430, binding = BINDING_NEXT_SAMPLES) writeonly buffer Final { vec4 finalSamples[]; };
layout(std430, binding = BINDING_NEXT_RADIANCE) writeonly buffer FinalRadiance { Record finalRadiance[]; };
uniform uint uLevel;  // k: its count is counts[k]
void main() {
  uint j = gl_GlobalInvocationID.x;
  if (j >= uCount || j >= counts[uLevel]) return;
  uint dst = counts[uEndSlot] + j;
  if (dst >= uCapacity) return;
  finalSamples[dst] = samples[j];
  finalRadiance[dst] = radiance[j];
}
#elif defined(SL_CHILD_SCATTER)
layout(std430, binding = BINDING_NEXT_SAMPLES) writeonly buffer Final { vec4 finalSamples[]; };
uniform vec3 uGridMin;
uniform vec3 uGridInterval;
uniform ivec3 uGridDims;
uniform float uRadius;
void main() {
  uint v = gl_GlobalInvocationID.x;
  if (v >= uCount || flags[v] == 0u) return;
  uint dst = counts[uEndSlot] + offsets[v];
  if (dst >= uCapacity) return;
  uint nx = uint(uGridDims.x), ny = uint(uGridDims.y);
  uint i = v % nx, j = (v / nx) % ny, k = v / (nx * ny);
  precise vec3 q = uGridMin + (vec3(float(i), float(j), float(k)) + 0.5) * uGridInterval;
  finalSamples[dst] = vec4(q, uRadius);
}
#else  // SL_ADVANCE
uniform uint uPartSlot;      // counts[slot]: receives the part's total
uniform uint uOverflowSlot;  // counts[slot]: the largest end asked beyond the capacity
uniform uint uCountSlot;     // 0xffffffff: the part's total from its scan; else counts[slot]
void main() {
  uint n = uCount;
  uint total = uCountSlot != 0xffffffffu ? min(counts[uCountSlot], n)
               : n == 0u                 ? 0u
                                         : offsets[n - 1u] + (flags[n - 1u] != 0u ? 1u : 0u);
  counts[uPartSlot] = total;
  uint end = counts[uEndSlot] + total;
  if (end > uCapacity) atomicMax(counts[uOverflowSlot], end);
  counts[uEndSlot] = min(end, uCapacity);
}
#endif
