// Normalises the splatted sums into the source-radiance volume: S = Σ W·taylor / Σ W. A voxel no
// sample covers is 0 unless it is occupied (VoxelOccupancy, cpu/per_voxel.h: density in its
// trilinear support; the same test as per_voxel.comp.glsl), which is counted as uncovered and,
// with SL_NEAREST_FILL (the compute gather), takes the value of the nearest sample (lowest index
// on ties), as the CPU reconstruction does (cpu/interpolation.cpp, uncoveredValue). A weight of
// −1 marks a voxel the gather left out (SL_LIT_REACH there): 0, not counted.
layout(local_size_x = 4, local_size_y = 4, local_size_z = 4) in;
layout(rgba32f, binding = BINDING_SUMS_IMAGE) uniform readonly image3D uSums;
layout(rgba32f, binding = BINDING_RADIANCE_IMAGE) uniform writeonly image3D uRadiance;
layout(binding = BINDING_DENSITY_TEXTURE) uniform sampler3D uDensity;
layout(std430, binding = BINDING_COUNTERS) buffer Counters { uint uncovered; };
uniform ivec3 uGridDims;
uniform bool uSameGrid;  // density and radiance share dims: alpha carries the voxel's density
uniform vec3 uGridMin;   // the radiance volume: voxel centres at min + (v + 0.5)·cell
uniform vec3 uGridCell;
uniform vec3 uDensityScale;  // world -> density index: u = p * scale + offset
uniform vec3 uDensityOffset;
uniform ivec3 uDensityDims;
#ifdef SL_NEAREST_FILL
struct FillRecord { vec4 S; vec4 dS[3]; };  // gpu::GpuRadianceRecord
layout(std430, binding = BINDING_SAMPLES) readonly buffer FillPoints { vec4 points[]; };
layout(std430, binding = BINDING_RADIANCE) readonly buffer FillRadiance { FillRecord records[]; };
#ifdef SL_COUNT_ON_DEVICE
// DeviceSampleList::count: the number of samples, known only on the GPU.
layout(std430, binding = BINDING_LEVEL_COUNTS) readonly buffer FillCount { uint fillCount; };
#else
uniform uint uSampleCount;
#endif
#endif

// VoxelOccupancy: a density voxel with D > 0 whose trilinear support overlaps the voxel's,
// the range shrunk by 1e-4 voxel against rounding.
bool occupied(vec3 c) {
  ivec3 lo = max(ivec3(floor((c - uGridCell) * uDensityScale + uDensityOffset + 1e-4)), ivec3(0));
  ivec3 hi = min(ivec3(ceil((c + uGridCell) * uDensityScale + uDensityOffset - 1e-4)),
                 uDensityDims - 1);
  for (int k = lo.z; k <= hi.z; ++k)
    for (int j = lo.y; j <= hi.y; ++j)
      for (int i = lo.x; i <= hi.x; ++i)
        if (texelFetch(uDensity, ivec3(i, j, k), 0).r > 0.0) return true;
  return false;
}

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
  precise vec3 c = uGridMin + (vec3(v) + 0.5) * uGridCell;
  if (!(s.a < 0.0) && occupied(c)) {
    atomicAdd(uncovered, 1u);
#ifdef SL_NEAREST_FILL
#ifdef SL_COUNT_ON_DEVICE
    const uint n = fillCount;
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
