// Per-voxel source radiance (the paper's baseline; cpu/per_voxel.cpp on the CPU): S traced
// at each voxel centre of the radiance volume, skipping voxels whose trilinear neighbourhood
// in the density volume is empty (identical to tracing them).
layout(local_size_x = 4, local_size_y = 4, local_size_z = 4) in;

#ifdef SL_LIGHT_PARTS
// Where the driver caps loop iterations the lights are split over dispatches
// (gpu::lightDispatches): this one takes lights uLightFirst, uLightFirst + uLightStride, …
// Without SL_FACTOR_LIGHTS it adds its part of S to what the parts before it stored (the first
// stores the skipped voxels and counts). With it, the parts add up FactoredSourceRadiance's sums
// in uSums0–3, and a last dispatch (uCombine 1) makes V of them, stores every voxel and counts.
layout(rgba32f, binding = BINDING_RADIANCE_IMAGE) uniform image3D uRadiance;
uniform int uLightFirst;
uniform int uLightStride;
#ifdef SL_FACTOR_LIGHTS
uniform int uCombine;
layout(rgba32f, binding = BINDING_PART_SUMS_IMAGE0) uniform image3D uSums0;  // s, outside
layout(rgba32f, binding = BINDING_PART_SUMS_IMAGE1) uniform image3D uSums1;  // a
layout(rgba32f, binding = BINDING_PART_SUMS_IMAGE2) uniform image3D uSums2;  // sf
layout(rgba32f, binding = BINDING_PART_SUMS_IMAGE3) uniform image3D uSums3;  // af
#endif
#else
layout(rgba32f, binding = BINDING_RADIANCE_IMAGE) uniform writeonly image3D uRadiance;
#endif
// Mirrored by gpu::GpuPerVoxelCounters (gpu/records.h); std430 offsets 0, 4.
layout(std430, binding = BINDING_COUNTERS) buffer Counters { uint traced; uint skipped; };
uniform ivec3 uRadDims;
uniform vec3 uRadMin;
uniform vec3 uRadCell;
uniform bool uSameGrid;  // the density's grid: alpha carries the voxel's density
#ifdef SL_LIT_REACH
// With SL_FACTOR_LIGHTS the march multiplies V by A: a voxel no spot cone reaches within its
// half-diagonal uReach is skipped too (buildPerVoxelRadiance's LitReach).
uniform float uReach;
#endif

void main() {
  ivec3 v = ivec3(gl_GlobalInvocationID);
  if (any(greaterThanEqual(v, uRadDims))) return;
  precise vec3 c = uRadMin + (vec3(v) + 0.5) * uRadCell;  // Grid3::cellCenter, as the CPU rounds it
  bool occupied = radianceVoxelOccupied(c, uRadCell);
#ifdef SL_LIT_REACH
  occupied = occupied && litReaches(c, uReach);
#endif
  float own = uSameGrid ? texelFetch(uDensity, v, 0).r : 0.0;
#ifdef SL_LIGHT_PARTS
  int stride = max(uLightStride, 1);
#ifdef SL_FACTOR_LIGHTS
  if (uCombine == 0) {
    if (!occupied) return;
    // Both sums of the part's lights: whether V needs the cones-ignored ones is known only
    // from every light's a, after the last part.
    vec3 toViewer = towardsEye(c), s, a, sf, af;
    float outside;
    factoredPart(c, toViewer, uLightFirst, stride, s, a, outside);
    factoredFreePart(c, toViewer, uLightFirst, stride, sf, af);
    if (uLightFirst > 0) {
      vec4 s0 = imageLoad(uSums0, v);
      s += s0.rgb;
      outside += s0.a;
      a += imageLoad(uSums1, v).rgb;
      sf += imageLoad(uSums2, v).rgb;
      af += imageLoad(uSums3, v).rgb;
    }
    imageStore(uSums0, v, vec4(s, outside));
    imageStore(uSums1, v, vec4(a, 0.0));
    imageStore(uSums2, v, vec4(sf, 0.0));
    imageStore(uSums3, v, vec4(af, 0.0));
    return;
  }
  if (occupied) {
    vec4 s0 = imageLoad(uSums0, v);
    vec3 a = imageLoad(uSums1, v).rgb;
    bool free = factoredNeedsFree(a, s0.a);
    vec3 V = factoredCombine(s0.rgb, a, free ? imageLoad(uSums2, v).rgb : vec3(0.0),
                             free ? imageLoad(uSums3, v).rgb : vec3(0.0));
#ifdef SL_LOG_SPACE
    V = log(max(V, vec3(SL_MIN_V)));
#endif
    imageStore(uRadiance, v, vec4(V, own));
    atomicAdd(traced, 1u);
    return;
  }
#else
  if (occupied) {
    vec3 S = sourceRadiancePart(c, towardsEye(c), uLightFirst, stride);
    if (uLightFirst > 0) S += imageLoad(uRadiance, v).rgb;
    else atomicAdd(traced, 1u);
    imageStore(uRadiance, v, vec4(S, own));
    return;
  }
  if (uLightFirst > 0) return;
#endif
#endif
  if (!occupied) {
    imageStore(uRadiance, v, vec4(0.0, 0.0, 0.0, own));
    atomicAdd(skipped, 1u);
    return;
  }
  imageStore(uRadiance, v, vec4(sourceTowardsEye(c), own));
  atomicAdd(traced, 1u);
}
