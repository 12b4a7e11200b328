// Per-voxel source radiance (the paper's baseline; cpu/per_voxel.cpp on the CPU): S traced
// at each voxel centre of the radiance volume, skipping voxels whose trilinear neighbourhood
// in the density volume is empty (identical to tracing them).
layout(local_size_x = 4, local_size_y = 4, local_size_z = 4) in;

layout(rgba32f, binding = BINDING_RADIANCE_IMAGE) uniform writeonly image3D uRadiance;
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
  vec3 c = uRadMin + (vec3(v) + 0.5) * uRadCell;
  bool occupied = radianceVoxelOccupied(c, uRadCell);
#ifdef SL_LIT_REACH
  occupied = occupied && litReaches(c, uReach);
#endif
  float own = uSameGrid ? texelFetch(uDensity, v, 0).r : 0.0;
  if (!occupied) {
    imageStore(uRadiance, v, vec4(0.0, 0.0, 0.0, own));
    atomicAdd(skipped, 1u);
    return;
  }
  imageStore(uRadiance, v, vec4(sourceTowardsEye(c), own));
  atomicAdd(traced, 1u);
}
