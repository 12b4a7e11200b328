// Radiance splatting (paper Sec. 4): for one slice of the radiance volume, instance j draws the
// bounding square of the circle where sample j's valid sphere cuts the slice plane.
// Mirrored by gpu::GpuSplatSample (gpu/records.h); std430 offsets positionRadius 0, S 16,
// dS 32 (stride 16), record stride 80.
struct SplatSample { vec4 positionRadius; vec4 S; vec4 dS[3]; };
layout(std430, binding = BINDING_SPLAT_SAMPLES) readonly buffer Samples { SplatSample samples[]; };
uniform vec3 uGridMin;
uniform vec3 uGridCell;
uniform ivec3 uGridDims;
uniform float uSliceZ;

flat out vec4 vPosR;
flat out vec3 vS;
flat out vec3 vDx;
flat out vec3 vDy;
flat out vec3 vDz;

void main() {
  SplatSample s = samples[gl_InstanceID];
  float R = s.positionRadius.w;
  float dz = uSliceZ - s.positionRadius.z;
  vPosR = s.positionRadius;
  vS = s.S.rgb;
  vDx = s.dS[0].rgb;
  vDy = s.dS[1].rgb;
  vDz = s.dS[2].rgb;
  if (abs(dz) >= R) {
    gl_Position = vec4(2.0, 2.0, 2.0, 1.0);
    return;
  }
  float rc = sqrt(R * R - dz * dz) + max(uGridCell.x, uGridCell.y);
  vec2 corner = vec2(gl_VertexID & 1, gl_VertexID >> 1) * 2.0 - 1.0;
  vec2 p = s.positionRadius.xy + corner * rc;
  vec2 ndc = (p - uGridMin.xy) / (uGridCell.xy * vec2(uGridDims.xy)) * 2.0 - 1.0;
  gl_Position = vec4(ndc, 0.0, 1.0);
}
