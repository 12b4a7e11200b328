// Normalises the splatted sums into the source-radiance volume: S = Σ W·taylor / Σ W, zero
// where no sample covers the voxel; counts covered-nothing voxels that hold density.
layout(local_size_x = 4, local_size_y = 4, local_size_z = 4) in;
layout(rgba32f, binding = BINDING_SUMS_IMAGE) uniform readonly image3D uSums;
layout(rgba32f, binding = BINDING_RADIANCE_IMAGE) uniform writeonly image3D uRadiance;
layout(binding = BINDING_DENSITY_TEXTURE) uniform sampler3D uDensity;
layout(std430, binding = BINDING_COUNTERS) buffer Counters { uint uncovered; };
uniform ivec3 uGridDims;
uniform vec3 uDensityLookupScale;  // radiance voxel index -> density texture coordinate
uniform vec3 uDensityLookupOffset;
uniform bool uSameGrid;  // density and radiance share dims: read the voxel itself, unfiltered

void main() {
  ivec3 v = ivec3(gl_GlobalInvocationID);
  if (any(greaterThanEqual(v, uGridDims))) return;
  vec4 s = imageLoad(uSums, v);
  // On the density's grid, alpha carries the voxel's density (gpu::Volume::densityInAlpha).
  float own = uSameGrid ? texelFetch(uDensity, v, 0).r : 0.0;
  if (s.a > 0.0) {
    // clampNonNegative of the CPU twin: Taylor extrapolation can go below zero at a shaft edge.
#ifdef SL_LOG_SPACE
    imageStore(uRadiance, v, vec4(exp(s.rgb / s.a), own));  // the samples held ln V
#else
    imageStore(uRadiance, v, vec4(max(s.rgb / s.a, vec3(0.0)), own));
#endif
  } else {
    imageStore(uRadiance, v, vec4(0.0, 0.0, 0.0, own));
    float D = uSameGrid ? own
                        : textureLod(uDensity, vec3(v) * uDensityLookupScale + uDensityLookupOffset, 0.0).r;
    if (D > 0.0) atomicAdd(uncovered, 1u);
  }
}
