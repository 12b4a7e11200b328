// A's far field (render.far_field; FarField of shading/transport.h, FarFieldCache of
// cpu/far_field.h): one invocation per vertex of the grid over the medium's box writes
// Σ_l w_l·A_l, w_l = farWeight (0 within R of a point light, 1 beyond 2R, 0 for the other
// lights), for the compute view march's farLookup. The isotropic phase only (the settings refuse
// the key otherwise), so A's terms do not depend on the direction to the viewer.
layout(local_size_x = 4, local_size_y = 4, local_size_z = 4) in;
// Names of its own (the march's are common.glsl's uFar*, under SL_FAR_FIELD).
// The grid, a texel per vertex (RGBA32F; gpu/bindings.h kFarFieldImage).
#ifdef SL_FAR_UPDATE
// In place (gpu::ViewMarchGpu): the terms of the uChangedCount lights uChanged[] of the lights
// bound now, times uSign, added to each vertex's sum: once with the lights before (−1), once
// with the lights now (+1).
layout(rgba32f, binding = BINDING_FAR_FIELD_IMAGE) uniform image3D farOut;
uniform int uChangedCount;
uniform int uChanged[32];
uniform float uSign;
#else
layout(rgba32f, binding = BINDING_FAR_FIELD_IMAGE) writeonly uniform image3D farOut;
#endif
uniform float uBuildR;
uniform vec3 uBuildLo;
uniform vec3 uBuildCell;
uniform ivec3 uBuildDims;
// The vertices computed (stats far_field_terms, read after the frame), summed per workgroup.
layout(std430, binding = BINDING_COUNTERS) buffer FarFieldCount { uint farVertices; };
shared uint groupVertices;

#ifdef SL_FAR_SKIP
// Only the vertices a march step can read (FarFieldCache on the CPU likewise, over its own
// bricks): the march looks the grid up at steps with density only, and a step in one of the 8
// cells around vertex x has its density lookup within one voxel of x, so where every block of
// the empty-space grid (gpu/empty_space.h; uBlockMax and uBlocks of block_walk.glsl, which the
// program then includes) those lookups fall in has maximum 0, no step reads x.
bool farVertexRead(vec3 x) {
  vec3 lo = (x - uBuildCell) * uDensityScale + uDensityOffset;
  vec3 hi = (x + uBuildCell) * uDensityScale + uDensityOffset;
  ivec3 b0 = clamp(ivec3(floor(max(lo, vec3(0.0)) / SL_BLOCK)), ivec3(0), uBlocks - 1);
  ivec3 b1 = clamp(ivec3(floor(max(hi, vec3(0.0)) / SL_BLOCK)), ivec3(0), uBlocks - 1);
  for (int z = b0.z; z <= b1.z; ++z)
    for (int y = b0.y; y <= b1.y; ++y)
      for (int x = b0.x; x <= b1.x; ++x)
        if (texelFetch(uBlockMax, ivec3(x, y, z), 0).r > 0.0) return true;
  return false;
}
#endif

void main() {
  if (gl_LocalInvocationIndex == 0u) groupVertices = 0u;
  memoryBarrierShared();
  barrier();
  ivec3 id = ivec3(gl_GlobalInvocationID);
  vec3 x = uBuildLo + vec3(id) * uBuildCell;
  bool inside = all(lessThan(id, uBuildDims));
#ifdef SL_FAR_SKIP
  bool read = inside && farVertexRead(x);
#else
  bool read = inside;
#endif
  if (read) {
    atomicAdd(groupVertices, 1u);
#ifdef SL_FAR_UPDATE
    vec3 a = imageLoad(farOut, id).xyz;
    for (int c = 0; c < uChangedCount; ++c) {
      int li = uChanged[c];
      float w = farWeight(li, x, uBuildR);
      if (w > 0.0) a += uSign * (w * lightFactorTerm(li, x, vec3(0.0, 0.0, 1.0)));
    }
#else
    vec3 a = vec3(0.0);
    for (int li = 0; li < uLightCount; ++li) {
      float w = farWeight(li, x, uBuildR);
      if (w > 0.0) a += w * lightFactorTerm(li, x, vec3(0.0, 0.0, 1.0));
    }
#endif
    imageStore(farOut, id, vec4(a, 0.0));
  }
#ifndef SL_FAR_UPDATE
  else if (inside) {
    imageStore(farOut, id, vec4(0.0));  // never read, but defined
  }
#endif
  memoryBarrierShared();
  barrier();
  if (gl_LocalInvocationIndex == 0u && groupVertices > 0u) atomicAdd(farVertices, groupVertices);
}
