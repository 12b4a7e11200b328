// Density construction by splatting (paper Sec. 6) as a gather (render.gpu_pipeline = compute;
// gpu::splatGaussians): each voxel centre x sums w·exp(−|x − c|²/r²) over the blobs whose
// culling sphere (kGaussianCullRadius·r) holds it, reading only its bin's list
// (gpu/sphere_bins.h: ascending blob order, the order in which density_splat.frag.glsl blends).
layout(local_size_x = 4, local_size_y = 4, local_size_z = 4) in;

struct Blob { vec4 centerRadius; vec4 weight; };  // gpu::GpuBlob
layout(std430, binding = BINDING_BLOBS) readonly buffer Blobs { Blob blobs[]; };
layout(std430, binding = BINDING_BIN_OFFSETS) readonly buffer BinOffsets { uint binOffsets[]; };
layout(std430, binding = BINDING_BIN_ITEMS) readonly buffer BinItems { uint binItems[]; };
layout(r32f, binding = BINDING_DENSITY_IMAGE) uniform writeonly image3D uDensityOut;
uniform vec3 uGridMin;
uniform vec3 uGridCell;
uniform ivec3 uGridDims;
uniform ivec3 uBins;
uniform int uBinVoxels;
uniform float uCull;

void main() {
  ivec3 v = ivec3(gl_GlobalInvocationID);
  if (any(greaterThanEqual(v, uGridDims))) return;
  vec3 x = vec3(uGridMin.xy + (vec2(v.xy) + 0.5) * uGridCell.xy,
                uGridMin.z + (float(v.z) + 0.5) * uGridCell.z);
  ivec3 b = v / uBinVoxels;
  int bin = (b.z * uBins.y + b.y) * uBins.x + b.x;
  float sum = 0.0;
  for (uint k = binOffsets[bin]; k < binOffsets[bin + 1]; ++k) {
    Blob blob = blobs[binItems[k]];
    vec3 d = x - blob.centerRadius.xyz;
    float q = dot(d, d);
    float R = uCull * blob.centerRadius.w, r2 = blob.centerRadius.w * blob.centerRadius.w;
    if (!(q < R * R)) continue;
    sum += blob.weight.x * exp(-q / r2);
  }
  imageStore(uDensityOut, v, vec4(sum));
}
