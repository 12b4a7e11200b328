// Dynamic sampling, splitting: one invocation per sample of level k (an indirect dispatch sized
// by the GPU); a sample whose E_j exceeds the threshold (compared in double, as the CPU
// compares, against the threshold the SL_THRESHOLD pass left on the GPU) marks every vertex of
// G_{k+1} strictly inside its valid sphere in the grid information buffer (inSet = 1) and lowers
// the vertex's ancestor with atomicMin. Mirrors GridInfoBuffer::markSphere; the index box is
// widened by one vertex on each side so that the sphere test alone (same float operations as the
// CPU, `precise`) decides membership.
// With a budget (scatterlab::budgetedSplit) the level runs twice: SL_BUDGET_KEYS first, where
// every candidate raises each of its vertices' keys to 1 + its error group (atomicMax: the
// group of the worst candidate that marks it) and counts itself in its group's candidate
// histogram (not on the per-voxel fallback's grid, where a split keeps its sample); then, once
// dynamic_budget.comp.glsl has cut the groups, SL_BUDGET, where only the candidates of groups at
// or above the level's cut (counts[uCutSlot]) split.
layout(local_size_x = 64) in;

layout(std430, binding = BINDING_SAMPLES) readonly buffer Samples { vec4 samples[]; };  // xyz, valid radius
layout(std430, binding = BINDING_ERRORS) readonly buffer Errors { float errors[]; };
layout(std430, binding = BINDING_LEVEL_COUNTS) readonly buffer LevelCounts { uint counts[]; };
layout(std430, binding = BINDING_THRESHOLD) readonly buffer Threshold { double errorScale; double threshold; };
#ifdef SL_BUDGET_KEYS
layout(std430, binding = BINDING_VERTEX_KEYS) buffer VertexKeys { uint vertexKeys[]; };
// [0, SL_ERROR_BINS): the candidates per group (the vertices' histogram follows)
layout(std430, binding = BINDING_GROUP_HISTOGRAMS) buffer Histograms { uint histograms[]; };
uniform uint uHistogramBase;  // the level's histograms in histograms[]
#else
layout(std430, binding = BINDING_ANCESTORS) readonly buffer Ancestors { int ancestors[]; };
layout(std430, binding = BINDING_IN_SET) buffer InSet { uint inSet[]; };
layout(std430, binding = BINDING_VERTEX_ANCESTORS) buffer VertexAncestor { int vertexAncestor[]; };  // INT_MAX = none
#endif
#ifdef SL_BUDGET
uniform uint uCutSlot;  // counts[slot]: the lowest error group of the level that splits
#endif

uniform uint uLevel;  // k: the level's sample count is counts[k]
uniform vec3 uGridMin;
uniform vec3 uGridInterval;
uniform ivec3 uGridDims;
uniform int uCell;  // 1: mark the cell, not the sphere (split "cell", and the per-voxel fallback)
uniform int uVoxels;  // 1: G_{k+1} is the per-voxel fallback's grid

void main() {
  uint s = SL_LINEAR_INVOCATION;
  if (s >= counts[uLevel] || !(double(errors[s]) > threshold)) return;
#if defined(SL_BUDGET_KEYS) || defined(SL_BUDGET)
  int group = errorGroup(errors[s], threshold);
#endif
#ifdef SL_BUDGET
  if (group < int(counts[uCutSlot])) return;
#endif
#ifdef SL_BUDGET_KEYS
  if (uVoxels == 0) atomicAdd(histograms[uHistogramBase + uint(group)], 1u);
  uint key = uint(group) + 1u;
#else
  int anc = ancestors[s];
#endif
  vec3 c = samples[s].xyz;
  float R = samples[s].w;
  ivec3 lo = max(ivec3(ceil((c - R - uGridMin) / uGridInterval - 0.5)) - 1, ivec3(0));
  ivec3 hi = min(ivec3(floor((c + R - uGridMin) / uGridInterval - 0.5)) + 1, uGridDims - 1);
  precise float R2 = R * R;
  precise vec3 ca = c - 0.5 * R, cb = c + 0.5 * R;
  for (int k = lo.z; k <= hi.z; ++k)
    for (int j = lo.y; j <= hi.y; ++j)
      for (int i = lo.x; i <= hi.x; ++i) {
        precise vec3 q = uGridMin + (vec3(i, j, k) + 0.5) * uGridInterval;
        if (uCell != 0) {
          // Split "cell" and the per-voxel fallback: the vertices in the sample's cell
          // [c − R/2, c + R/2) (GridInfoBuffer::forEachInCell).
          if (any(lessThan(q, ca)) || !all(lessThan(q, cb))) continue;
        } else {
          precise vec3 d = q - c;
          precise float d2 = d.x * d.x + d.y * d.y + d.z * d.z;
          if (d2 >= R2) continue;
        }
        uint v = (uint(k) * uint(uGridDims.y) + uint(j)) * uint(uGridDims.x) + uint(i);
#ifdef SL_BUDGET_KEYS
        atomicMax(vertexKeys[v], key);
#else
        inSet[v] = 1u;
        atomicMin(vertexAncestor[v], anc);
#endif
      }
}
