// After common.glsl (the density's uniforms, RadianceRecord, radianceVoxelOccupied).
// Normalises the splatted sums into the source-radiance volume: S = Σ W·taylor / Σ W. A voxel no
// sample covers is 0 unless it is occupied (radianceVoxelOccupied: density in its trilinear
// support, as per_voxel.comp.glsl skips), which is counted as uncovered and, with SL_NEAREST_FILL (the compute gather), takes the value of the nearest sample (lowest index
// on ties), as the CPU reconstruction does (cpu/interpolation.cpp, uncoveredValue). A weight of
// −1 marks a voxel the gather left out (SL_LIT_REACH there): 0, not counted.
// The nearest samples depend on the positions, the radii, the density and the grid, not on the
// lights (gpu::NearestFill): SL_FILL_RECORD appends each (voxel, sample) found to a
// list; SL_FILL_KEPT (a later frame with the same samples) does not search unless that list
// overflowed, and SL_FILL_PASS, run after it, writes the listed voxels from the list.
#ifdef SL_FILL_PASS
layout(local_size_x = 64) in;
#else
layout(local_size_x = 4, local_size_y = 4, local_size_z = 4) in;
#endif
layout(rgba32f, binding = BINDING_SUMS_IMAGE) uniform readonly image3D uSums;
layout(rgba32f, binding = BINDING_RADIANCE_IMAGE) uniform writeonly image3D uRadiance;
layout(std430, binding = BINDING_COUNTERS) buffer Counters { uint uncovered; };
uniform ivec3 uGridDims;
uniform bool uSameGrid;  // density and radiance share dims: alpha carries the voxel's density
uniform vec3 uGridMin;   // the radiance volume: voxel centres at min + (v + 0.5)·cell
uniform vec3 uGridCell;
#if defined(SL_NEAREST_FILL) || defined(SL_FILL_PASS)
layout(std430, binding = BINDING_RADIANCE) readonly buffer FillRadiance { RadianceRecord records[]; };
#endif
#if defined(SL_FILL_RECORD) || defined(SL_FILL_KEPT) || defined(SL_FILL_PASS)
layout(std430, binding = BINDING_FILL_ENTRIES) buffer FillEntries { uvec2 fillEntries[]; };
layout(std430, binding = BINDING_FILL_WORDS) buffer FillWords { uint fillCount; uint fillOverflow; };
uniform uint uFillCapacity;
#endif
#ifdef SL_NEAREST_FILL
layout(std430, binding = BINDING_SAMPLES) readonly buffer FillPoints { vec4 points[]; };
#ifdef SL_COUNT_ON_DEVICE
// DeviceSampleList::count: the number of samples, known only on the GPU.
layout(std430, binding = BINDING_LEVEL_COUNTS) readonly buffer SampleCount { uint sampleCount; };
#else
uniform uint uSampleCount;
#endif
#endif

#ifdef SL_FILL_PASS
// The kept list's voxels, after the normalisation wrote them 0 (nothing when it overflowed:
// the normalisation searched then).
void main() {
  if (fillOverflow != 0u) return;
  const uint n = min(fillCount, uFillCapacity);
  if (gl_GlobalInvocationID.x == 0u) uncovered = n;  // the normalisation counted none
  // The workgroups stride over the entries (a dispatch of at most 1024 whatever the count).
  for (uint i = gl_GlobalInvocationID.x; i < n; i += gl_NumWorkGroups.x * gl_WorkGroupSize.x) {
    const uvec2 e = fillEntries[i];
    const ivec3 v = ivec3(int(e.x) % uGridDims.x, int(e.x) / uGridDims.x % uGridDims.y,
                          int(e.x) / (uGridDims.x * uGridDims.y));
    float own = uSameGrid ? texelFetch(uDensity, v, 0).r : 0.0;
    vec3 value = vec3(0.0);
    if (int(e.y) >= 0) {
      vec3 S = records[e.y].S.rgb;
#ifdef SL_LOG_SPACE
      value = exp(S);
#else
      value = max(S, vec3(0.0));
#endif
    }
    imageStore(uRadiance, v, vec4(value, own));
  }
}
#else
void main() {
  ivec3 v = ivec3(gl_GlobalInvocationID);
  if (any(greaterThanEqual(v, uGridDims))) return;
  vec4 s = imageLoad(uSums, v);
  float own = uSameGrid ? texelFetch(uDensity, v, 0).r : 0.0;
  if (s.a > 0.0) {
    // clampNonNegative of the CPU twin: Taylor extrapolation can go below zero at a shaft edge.
#ifdef SL_LOG_SPACE
    imageStore(uRadiance, v, vec4(exp(s.rgb / s.a), own));  // the samples held ln V
#else
    imageStore(uRadiance, v, vec4(max(s.rgb / s.a, vec3(0.0)), own));
#endif
    return;
  }
  vec3 value = vec3(0.0);
#ifdef SL_FILL_KEPT
  if (fillOverflow == 0u) {
    // The uncovered voxels are the kept list's: SL_FILL_PASS writes them and their count.
    imageStore(uRadiance, v, vec4(value, own));
    return;
  }
#endif
  precise vec3 c = uGridMin + (vec3(v) + 0.5) * uGridCell;
  if (!(s.a < 0.0) && radianceVoxelOccupied(c, uGridCell)) {
    atomicAdd(uncovered, 1u);
#ifdef SL_NEAREST_FILL
#ifdef SL_COUNT_ON_DEVICE
    const uint n = sampleCount;
#else
    const uint n = uSampleCount;
#endif
    float best = 3.4028235e38;  // FLT_MAX
    int nearest = -1;
    for (uint j = 0u; j < n; ++j) {
      precise vec3 d = c - points[j].xyz;
      precise float d2 = d.x * d.x + d.y * d.y + d.z * d.z;
      if (d2 < best) {
        best = d2;
        nearest = int(j);
      }
    }
#ifdef SL_FILL_RECORD
    const uint slot = atomicAdd(fillCount, 1u);
    if (slot < uFillCapacity)
      fillEntries[slot] = uvec2(uint((v.z * uGridDims.y + v.y) * uGridDims.x + v.x), uint(nearest));
    else
      fillOverflow = 1u;
#endif
    if (nearest >= 0) {
      vec3 S = records[nearest].S.rgb;
#ifdef SL_LOG_SPACE
      value = exp(S);
#else
      value = max(S, vec3(0.0));
#endif
    }
#endif
  }
  imageStore(uRadiance, v, vec4(value, own));
}
#endif
