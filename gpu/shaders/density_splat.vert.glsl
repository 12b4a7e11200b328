// Density construction by splatting (paper Sec. 6): for one slice z of the density volume,
// instance j draws the bounding square of blob j's culling sphere (3 r) cut by the slice plane.
// Mirrored by gpu::GpuBlob (gpu/records.h); std430 offsets 0, 16, stride 32.
struct Blob { vec4 centerRadius; vec4 weight; };
layout(std430, binding = BINDING_BLOBS) readonly buffer Blobs { Blob blobs[]; };
uniform vec3 uGridMin;
uniform vec3 uGridCell;
uniform ivec3 uGridDims;
uniform float uSliceZ;  // world z of this slice's voxel centres
uniform float uCull;    // culling radius in units of r

flat out vec4 vBlob;  // centre, r
flat out float vWeight;

void main() {
  Blob b = blobs[gl_InstanceID];
  float R = uCull * b.centerRadius.w;
  float dz = uSliceZ - b.centerRadius.z;
  vBlob = b.centerRadius;
  vWeight = b.weight.x;
  if (abs(dz) >= R) {  // this slice misses the blob: degenerate, culled
    gl_Position = vec4(2.0, 2.0, 2.0, 1.0);
    return;
  }
  float rc = sqrt(R * R - dz * dz) + max(uGridCell.x, uGridCell.y);  // one cell of margin
  vec2 corner = vec2(gl_VertexID & 1, gl_VertexID >> 1) * 2.0 - 1.0;
  vec2 p = b.centerRadius.xy + corner * rc;
  vec2 ndc = (p - uGridMin.xy) / (uGridCell.xy * vec2(uGridDims.xy)) * 2.0 - 1.0;
  gl_Position = vec4(ndc, 0.0, 1.0);
}
