// Adds w·exp(−|x − c|²/r²) at this voxel centre when it lies within the culling sphere
// (GaussianDensity::build). Blending GL_ONE/GL_ONE sums blobs in primitive (= blob) order.
uniform vec3 uGridMin;
uniform vec3 uGridCell;
uniform float uSliceZ;
uniform float uCull;
flat in vec4 vBlob;
flat in float vWeight;
layout(location = 0) out float outDensity;

void main() {
  vec3 x = vec3(uGridMin.xy + gl_FragCoord.xy * uGridCell.xy, uSliceZ);
  vec3 v = x - vBlob.xyz;
  float q = dot(v, v);
  float R = uCull * vBlob.w, r2 = vBlob.w * vBlob.w;
  if (!(q < R * R)) discard;
  outDensity = vWeight * exp(-q / r2);
}
