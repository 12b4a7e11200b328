// Dynamic sampling's budget on the GPU (scatterlab::budgetedSplit and budgetTopUp,
// sampling/dynamic_sampling.h): the worst-first cut of a level's error groups, decided from two
// histograms without the host.
// SL_VERTEX_GROUPS (after dynamic_split.comp.glsl's SL_BUDGET_KEYS): one invocation per vertex
// of G_{k+1}; a marked vertex counts in the vertices' histogram under its key's group.
// SL_CUT (one workgroup): with delta[g] = vertices − candidates of group g, counted twice — in
// the budget's units (a vertex of the per-voxel fallback's grid weighs 1, every other sample
// uUnit: scatterlab::BudgetLimits) and in samples — and run(h) = count + Σ_{g >= h} delta[g],
// the cut is one above the highest group h whose run exceeds the units' limit or the samples'
// (0: all groups fit; SL_ERROR_BINS: none does), as scatterlab's worstFirstCut. For a level
// (uTopUp = 0) count = the samples kept so far + the level's, the units' limit = count +
// max(0, budget − count) / (split levels left), the samples' uSampleLimit; it writes the cut,
// the count after it (units), and the samples kept after the level, in units and in samples
// (those of the cut groups split, unless the level splits into the per-voxel fallback's
// grid). For the top-up (uTopUp = 1) delta sums every split level's histograms below its cut,
// count = the pass's final count, the limits the budget's (no top-up when the count is
// already at the budget).
const int kBins = int(SL_ERROR_BINS);  // the error groups (core/stages.h kErrorBins)
#ifdef SL_VERTEX_GROUPS
layout(local_size_x = 256) in;
layout(std430, binding = BINDING_VERTEX_KEYS) readonly buffer VertexKeys { uint vertexKeys[]; };
layout(std430, binding = BINDING_GROUP_HISTOGRAMS) buffer Histograms { uint histograms[]; };
uniform uint uVertexCount;
uniform uint uHistogramBase;  // the level's candidates' histogram; the vertices' follows it

void main() {
  uint v = SL_LINEAR_INVOCATION;
  if (v >= uVertexCount) return;
  uint key = vertexKeys[v];
  if (key > 0u) atomicAdd(histograms[uHistogramBase + uint(kBins) + key - 1u], 1u);
}
#else
#define THREADS 1024
#define PER_THREAD 4  // kBins / THREADS (gpu/dynamic_sampling.cpp asserts it)
layout(local_size_x = THREADS) in;
layout(std430, binding = BINDING_LEVEL_COUNTS) buffer LevelCounts { uint counts[]; };
layout(std430, binding = BINDING_GROUP_HISTOGRAMS) readonly buffer Histograms { uint histograms[]; };
uniform uint uLevel;        // k (the top-up: L, the final level)
uniform uint uSplitLevels;  // L
uniform int uTopUp;
uniform int uBudget;        // the budget in units (clamped to the int range)
uniform int uSampleLimit;   // the most samples of the final list (clamped to the int range)
uniform int uUnit;          // a sample's weight in units (a fallback voxel's: 1)
uniform int uFallback;      // 1: level uSplitLevels is the per-voxel fallback's grid
uniform uint uKeptSlot;     // counts[slot]: the samples of the coarser levels that stay (units)
uniform uint uKeptSamplesSlot;  // counts[slot]: the same in samples
uniform uint uCountSlot;    // counts[slot]: the count after the cut
uniform uint uCutSlot;      // counts[slot]: the cut (the level's, or the top-up's)
uniform uint uCutsSlot;     // counts[slot + l]: the cut of split level l (the top-up reads them)

shared int suffix[THREADS];
shared int suffixSamples[THREADS];
shared int highestFail;
shared int afterCut;
shared int candidatesCut;

// The weight of a sample of level l in units.
int levelUnit(uint l) {
  return uFallback != 0 && l == uSplitLevels ? 1 : uUnit;
}

// Group g's delta in units; its candidates and its delta in samples through the out parameters.
int delta(int g, out int candidates, out int samples) {
  if (uTopUp == 0) {
    uint base = uLevel * 2u * uint(kBins);
    candidates = int(histograms[base + uint(g)]);
    int vertices = int(histograms[base + uint(kBins) + uint(g)]);
    samples = vertices - candidates;
    return vertices * levelUnit(uLevel + 1u) - candidates * uUnit;
  }
  candidates = 0;
  samples = 0;
  int d = 0;
  for (uint l = 0u; l < uSplitLevels; ++l) {
    if (g >= int(counts[uCutsSlot + l])) continue;
    uint base = l * 2u * uint(kBins);
    int c = int(histograms[base + uint(g)]);
    int vertices = int(histograms[base + uint(kBins) + uint(g)]);
    samples += vertices - c;
    d += vertices * levelUnit(l + 1u) - c * uUnit;
  }
  return d;
}

void main() {
  int t = int(gl_LocalInvocationID.x);
  int kept = int(counts[uKeptSlot]);
  int count = kept + int(counts[uLevel]) * levelUnit(uLevel);
  int countSamples = int(counts[uKeptSamplesSlot]) + int(counts[uLevel]);
  int limit = uTopUp == 0 ? count + max(0, uBudget - count) / int(uSplitLevels - uLevel) : uBudget;
  bool none = uTopUp != 0 && count >= uBudget;
  int d[PER_THREAD], c[PER_THREAD], n[PER_THREAD];
  int mine = 0, mineSamples = 0;
  for (int i = 0; i < PER_THREAD; ++i) {
    d[i] = delta(t * PER_THREAD + i, c[i], n[i]);
    mine += d[i];
    mineSamples += n[i];
  }
  if (t == 0) {
    highestFail = -1;
    afterCut = 0;
    candidatesCut = 0;
  }
  suffix[t] = mine;
  suffixSamples[t] = mineSamples;
  // Inclusive suffix sums over the threads (Hillis–Steele): suffix[t] = Σ_{t' >= t} mine.
  for (int stride = 1; stride < THREADS; stride *= 2) {
    memoryBarrierShared();
    barrier();
    int add = t + stride < THREADS ? suffix[t + stride] : 0;
    int addSamples = t + stride < THREADS ? suffixSamples[t + stride] : 0;
    memoryBarrierShared();
    barrier();
    suffix[t] += add;
    suffixSamples[t] += addSamples;
  }
  memoryBarrierShared();
  barrier();
  // run(g) for this thread's groups, from its highest down.
  int run = count + (t + 1 < THREADS ? suffix[t + 1] : 0);
  int runSamples = countSamples + (t + 1 < THREADS ? suffixSamples[t + 1] : 0);
  int fail = -1;
  for (int i = PER_THREAD - 1; i >= 0; --i) {
    run += d[i];
    runSamples += n[i];
    if ((run > limit || runSamples > uSampleLimit) && fail < 0) fail = t * PER_THREAD + i;
  }
  if (fail >= 0) atomicMax(highestFail, fail);
  memoryBarrierShared();
  barrier();
  int cut = none ? kBins : highestFail + 1;
  for (int i = 0; i < PER_THREAD; ++i)
    if (t * PER_THREAD + i >= cut) {
      atomicAdd(afterCut, d[i]);
      atomicAdd(candidatesCut, c[i]);
    }
  memoryBarrierShared();
  barrier();
  if (t == 0) {
    counts[uCutSlot] = uint(cut);
    counts[uCountSlot] = uint(count + afterCut);
    if (uTopUp == 0) {
      counts[uKeptSlot] = uint(count - candidatesCut * uUnit);
      counts[uKeptSamplesSlot] = uint(countSamples - candidatesCut);
    }
  }
}
#endif
