// Dynamic sampling, the per-level bookkeeping that stays on the GPU (one invocation):
// SL_THRESHOLD (after level 0's evaluation): the error scale of a relative ε, the mean of the
// level-0 contributions summed in index order in double (relativeErrorScale), and the absolute
// threshold ε·scale (or ε), both as doubles for the split pass and the host's read-back.
// Without it (after the scan of G_{k+1}'s membership): |Q^{k+1}| = last offset + last flag,
// clamped to the level's capacity (an overflow records the largest asked count and its level,
// reported by the host once the frame is done), and the level's indirect dispatch sizes (64
// samples per workgroup, 8 for the evaluate pass with tau "visible", and the tracer's and the
// probe pass's: uSamplesPerGroup a workgroup, at most uMaxTraceGroups, the probes' groups in y).
layout(local_size_x = 1) in;

layout(std430, binding = BINDING_LEVEL_COUNTS) buffer LevelCounts { uint counts[]; };

#ifdef SL_THRESHOLD
// E_j at [j], the contributions at [count + j] (level 0)
layout(std430, binding = BINDING_ERRORS) readonly buffer Errors { float errors[]; };
layout(std430, binding = BINDING_THRESHOLD) writeonly buffer Threshold { double errorScale; double threshold; };
uniform double uEpsilon;
uniform int uRelative;

void main() {
  uint n = counts[0];
  precise double scale = 0.0;
  if (uRelative != 0 && n > 0u) {
    precise double sum = 0.0;
    for (uint j = 0u; j < n; ++j) sum += double(errors[n + j]);
    scale = sum / double(n);
  }
  errorScale = scale;
  threshold = uRelative != 0 ? uEpsilon * scale : uEpsilon;
}
#else
layout(std430, binding = BINDING_IN_SET) readonly buffer InSet { uint inSet[]; };
layout(std430, binding = BINDING_OFFSETS) readonly buffer Offsets { uint offsets[]; };
uniform uint uVertexCount;  // vertices of G_{k+1}
uniform uint uLevel;        // k + 1
uniform uint uCapacity;     // the level's sample capacity
uniform uint uOverflowSlot; // counts[slot]: largest asked count, counts[slot + 1]: its level
uniform uint uDispatchSlot; // counts[slot + 3·level ...]: the level's (x, 1, 1) dispatch
uniform uint uEvaluateSlot; // likewise, its evaluate pass's with tau "visible" (8 per workgroup)
uniform uint uMaxEvaluateGroups;  // at most this many workgroups (they stride over the rest)
uniform uint uTraceSlot;    // counts[slot + 3·level ...]: the level's tracer pass (x, 1, 1)
uniform uint uProbesSlot;   // likewise its probe pass (x, probe groups, 1); 0 groups: not probed
uniform uint uSamplesPerGroup;  // samples a workgroup of either pass holds (the tracer's slots)
uniform uint uProbeGroups;
uniform uint uMaxTraceGroups;
uniform uint uLinearFold;   // gpu/dispatch.h linearFold()

void main() {
  uint n = uVertexCount;
  uint total = n == 0u ? 0u : offsets[n - 1u] + (inSet[n - 1u] != 0u ? 1u : 0u);
  uint kept = min(total, uCapacity);
  counts[uLevel] = kept;
  if (total > uCapacity) {
    atomicMax(counts[uOverflowSlot], total);
    atomicMax(counts[uOverflowSlot + 1u], uLevel);
  }
  uint d = uDispatchSlot + 3u * uLevel;
  uint g = (kept + 63u) / 64u;  // laid out as gpu/dispatch.h linearDispatch: rows of uLinearFold
  counts[d] = min(g, uLinearFold);
  counts[d + 1u] = max((g + uLinearFold - 1u) / uLinearFold, 1u);
  counts[d + 2u] = 1u;
  uint e = uEvaluateSlot + 3u * uLevel;
  counts[e] = min((kept + 7u) / 8u, uMaxEvaluateGroups);
  counts[e + 1u] = 1u;
  counts[e + 2u] = 1u;
  uint groups = min((kept + uSamplesPerGroup - 1u) / uSamplesPerGroup, uMaxTraceGroups);
  uint t = uTraceSlot + 3u * uLevel;
  counts[t] = groups;
  counts[t + 1u] = 1u;
  counts[t + 2u] = 1u;
  uint p = uProbesSlot + 3u * uLevel;
  counts[p] = uProbeGroups == 0u ? 0u : groups;
  counts[p + 1u] = max(uProbeGroups, 1u);
  counts[p + 2u] = 1u;
}
#endif
