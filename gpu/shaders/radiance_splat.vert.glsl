// Radiance splatting (paper Sec. 4): for one slice of the radiance volume, instance j draws the
// bounding square of the circle where sample j's valid sphere cuts the slice plane.
struct Sample { vec4 positionRadius; vec4 S; vec4 dSx; vec4 dSy; vec4 dSz; };
layout(std430, binding = 1) readonly buffer Samples { Sample samples[]; };
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
  Sample s = samples[gl_InstanceID];
  float R = s.positionRadius.w;
  float dz = uSliceZ - s.positionRadius.z;
  vPosR = s.positionRadius;
  vS = s.S.rgb;
  vDx = s.dSx.rgb;
  vDy = s.dSy.rgb;
  vDz = s.dSz.rgb;
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
