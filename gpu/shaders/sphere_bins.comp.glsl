// The compute gathers' sphere bins built on the GPU (gpu::binSpheresGpu), from spheres whose
// count only the GPU knows: the lists of gpu::binSpheres (gpu/sphere_bins.cpp), which see each
// sphere's bin range the same way. Three passes, the host scanning between the first two:
// SL_BINS_COUNT: per sphere, +1 to the count of every bin its range covers (the host then scans
//   the counts into the lists' offsets);
// SL_BINS_FILL: per sphere, its index into a slot of every such bin's list, taking the slots by
//   counting the bin's count back down (so the counts end at 0); entries at or past
//   uItemCapacity are dropped and the entries needed recorded in `overflow`;
// SL_BINS_SORT: per bin (one workgroup), its list sorted ascending: the atomics hand out the
//   slots in no set order, and the gathers must sum each voxel's spheres in ascending order
//   (the rasterised splat's, and the same bits every run).
// Bin (x, y, z), index (z·bins.y + y)·bins.x + x, holds voxels [kb, kb + k) along each axis,
// k = uBinVoxels (gpu::kBinVoxels).

#ifndef SL_BINS_SORT
layout(local_size_x = 64) in;

layout(std430, binding = BINDING_SAMPLES) readonly buffer BinSpheres { vec4 spheres[]; };  // xyz, r
layout(std430, binding = BINDING_BIN_SPHERE_COUNT) readonly buffer BinSphereCount { uint sphereCount[]; };
layout(std430, binding = BINDING_BIN_COUNTS) buffer BinCounts { uint binCounts[]; };
uniform uint uCountSlot;  // the spheres are spheres[0, min(sphereCount[uCountSlot], uCapacity))
uniform uint uCapacity;
uniform vec3 uGridMin;
uniform vec3 uGridInvCell;  // the host's 1 / (extent / dims), so that the same floats go in
uniform ivec3 uGridDims;
uniform ivec3 uBins;
uniform int uBinVoxels;

// binRange of gpu/sphere_bins.cpp, expression for expression: the bins [lo, hi] of the voxel
// centres within [c − r, c + r] along one axis, one voxel of margin; false when the sphere misses
// the grid (or c or r is NaN). `precise` keeps the compiler from reassociating or contracting
// them. A product, not a division: a float product rounds alike on every IEEE device, so the bins
// equal the host's on any GPU (a division, off by an ulp or two on NVIDIA, could move a boundary:
// the voxel of margin absorbed it, as the gathers test the exact distance, never the bin, but
// the lists differed from the host's). The comparisons are
// written so that NaN reads as a miss (both are false for it), never negated.
bool binRange(float c, float r, float lower, float invCell, int dims, out int lo, out int hi) {
  precise float a = floor((c - r - lower) * invCell - 0.5) - 1.0;
  precise float b = ceil((c + r - lower) * invCell - 0.5) + 1.0;
  lo = 1;
  hi = 0;
  if (b >= 0.0 && a <= float(dims - 1)) {
    lo = max(0, int(max(a, 0.0))) / uBinVoxels;
    hi = min(dims - 1, int(min(b, float(dims - 1)))) / uBinVoxels;
  }
  return lo <= hi;
}

#ifdef SL_BINS_FILL
layout(std430, binding = BINDING_BIN_OFFSETS) readonly buffer BinOffsets { uint binOffsets[]; };
layout(std430, binding = BINDING_BIN_ITEMS) writeonly buffer BinItems { uint binItems[]; };
layout(std430, binding = BINDING_BIN_OVERFLOW) writeonly buffer BinOverflow { uint overflow; };
uniform uint uItemCapacity;
#endif

void main() {
  // Workgroups in 2D, so that any capacity fits the dispatch limits.
  uint j = (gl_WorkGroupID.y * gl_NumWorkGroups.x + gl_WorkGroupID.x) * gl_WorkGroupSize.x +
           gl_LocalInvocationID.x;
#ifdef SL_BINS_FILL
  if (j == 0u) {
    uint total = binOffsets[uBins.x * uBins.y * uBins.z];
    overflow = total > uItemCapacity ? total : 0u;
  }
#endif
  if (j >= min(sphereCount[uCountSlot], uCapacity)) return;
  vec4 s = spheres[j];
  ivec3 lo, hi;
  bool hit = binRange(s.x, s.w, uGridMin.x, uGridInvCell.x, uGridDims.x, lo.x, hi.x);
  hit = binRange(s.y, s.w, uGridMin.y, uGridInvCell.y, uGridDims.y, lo.y, hi.y) && hit;
  hit = binRange(s.z, s.w, uGridMin.z, uGridInvCell.z, uGridDims.z, lo.z, hi.z) && hit;
  if (hit && s.w > 0.0) {
    for (int z = lo.z; z <= hi.z; ++z)
      for (int y = lo.y; y <= hi.y; ++y)
        for (int x = lo.x; x <= hi.x; ++x) {
          uint b = uint((z * uBins.y + y) * uBins.x + x);
#ifdef SL_BINS_FILL
          uint k = binOffsets[b] + atomicAdd(binCounts[b], 0xffffffffu) - 1u;
          if (k < uItemCapacity) binItems[k] = j;
#else
          atomicAdd(binCounts[b], 1u);
#endif
        }
  }
}

#else  // SL_BINS_SORT

// A bitonic sorting network over the bin's n entries, in the variant whose every comparator
// puts the smaller at the lower index (the first step of each merge compares mirrored pairs), so
// that n need not be a power of two: the missing entries past n read as +∞, and a comparator
// that reaches one is skipped. Entries are distinct (a sphere is listed once per bin). In shared
// memory up to SORT_SHARED entries, in the list itself beyond. After an overflow each offset is
// clamped to uItemCapacity, so that a gather reads within the lists (wrong sums, which the
// caller reports from the overflow word).
#define SORT_SHARED 2048u
layout(local_size_x = 64) in;

layout(std430, binding = BINDING_BIN_OFFSETS) buffer BinOffsets { uint binOffsets[]; };
layout(std430, binding = BINDING_BIN_ITEMS) coherent buffer BinItems { uint binItems[]; };
uniform uint uItemCapacity;
uniform ivec3 uBins;
shared uint keys[SORT_SHARED];

// Comparator p (of size/2, size = n rounded up to a power of two) of the step at distance
// `dist` of the merge into sorted blocks of `block`: its lower index, and in `upper` its other
// one (the mirrored entry in the merge's first step, dist = block/2; i + dist after it).
uint comparator(uint p, uint block, uint dist, out uint upper) {
  uint i = 2u * dist * (p / dist) + p % dist;
  upper = dist == block / 2u ? i ^ (block - 1u) : i + dist;
  return i;
}

void main() {
  uint bin = (gl_WorkGroupID.z * uint(uBins.y) + gl_WorkGroupID.y) * uint(uBins.x) + gl_WorkGroupID.x;
  uint t = gl_LocalInvocationID.x;
  // Another workgroup may clamp offsets[bin] or [bin + 1] while this one reads it; either value
  // gives the same minimum.
  uint lo = min(binOffsets[bin], uItemCapacity);
  uint hi = min(binOffsets[bin + 1u], uItemCapacity);
  if (t == 0u && binOffsets[bin] > uItemCapacity) binOffsets[bin] = uItemCapacity;
  uint last = uint(uBins.x * uBins.y * uBins.z) - 1u;
  if (t == 0u && bin == last && binOffsets[bin + 1u] > uItemCapacity)
    binOffsets[bin + 1u] = uItemCapacity;
  uint n = hi - lo;  // the same for the whole workgroup
  if (n <= 1u) return;
  uint size = 2u;
  while (size < n) size <<= 1;
  uint pairs = size / 2u;
  if (n <= SORT_SHARED) {
    for (uint i = t; i < n; i += gl_WorkGroupSize.x) keys[i] = binItems[lo + i];
    for (uint block = 2u; block <= size; block <<= 1)
      for (uint dist = block / 2u; dist > 0u; dist >>= 1) {
        memoryBarrierShared();
        barrier();
        for (uint p = t; p < pairs; p += gl_WorkGroupSize.x) {
          uint u;
          uint i = comparator(p, block, dist, u);
          if (u < n && keys[u] < keys[i]) {
            uint x = keys[i];
            keys[i] = keys[u];
            keys[u] = x;
          }
        }
      }
    memoryBarrierShared();
    barrier();
    for (uint i = t; i < n; i += gl_WorkGroupSize.x) binItems[lo + i] = keys[i];
  } else {
    for (uint block = 2u; block <= size; block <<= 1)
      for (uint dist = block / 2u; dist > 0u; dist >>= 1) {
        memoryBarrierBuffer();
        barrier();
        for (uint p = t; p < pairs; p += gl_WorkGroupSize.x) {
          uint u;
          uint i = comparator(p, block, dist, u);
          if (u < n && binItems[lo + u] < binItems[lo + i]) {
            uint x = binItems[lo + i];
            binItems[lo + i] = binItems[lo + u];
            binItems[lo + u] = x;
          }
        }
      }
  }
}
#endif
