// MaxDensityGrid (core/max_density_grid.h) on the GPU, the compute view march's empty-space
// skipping grid (gpu/empty_space.h): per block of SL_BLOCK³ voxels, the largest density any
// trilinear lookup within one voxel of the block can read, i.e. the maximum over voxels
// [b·B − 1, (b + 1)·B + 1] clamped to the grid. One invocation per block. After common.glsl.
layout(local_size_x = 4, local_size_y = 4, local_size_z = 4) in;

layout(r32f, binding = BINDING_BLOCK_MAX_IMAGE) uniform writeonly image3D uBlockMaxOut;
uniform ivec3 uBlockCount;

void main() {
  ivec3 b = ivec3(gl_GlobalInvocationID);
  if (any(greaterThanEqual(b, uBlockCount))) return;
  const int B = int(SL_BLOCK);
  ivec3 lo = max(b * B - 1, ivec3(0));
  ivec3 hi = min((b + 1) * B + 1, uDensityDims - 1);
  float m = 0.0;
  for (int k = lo.z; k <= hi.z; ++k)
    for (int j = lo.y; j <= hi.y; ++j)
      for (int i = lo.x; i <= hi.x; ++i) m = max(m, texelFetch(uDensity, ivec3(i, j, k), 0).r);
  imageStore(uBlockMaxOut, b, vec4(m));
}
