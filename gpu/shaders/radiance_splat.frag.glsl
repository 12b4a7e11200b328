// Adds (W·(S_j + (x − x_j)·∇S_j), W) with W = R_j/‖x − x_j‖ (paper Eq. 4) for voxel centres
// inside the valid sphere; blending GL_ONE/GL_ONE into an RGBA32F layer.
uniform vec3 uGridMin;
uniform vec3 uGridCell;
uniform float uSliceZ;
#ifdef SL_OCCLUSION
uniform float uDensityVoxel;  // smallest density voxel edge (world units)
#endif
#ifdef SL_BOUNDED
uniform vec2 uTaylorBounds;  // TaylorBounds (lo, hi): each Taylor estimate is clamped to it
#endif
flat in vec4 vPosR;
flat in vec3 vS;
flat in vec3 vDx;
flat in vec3 vDy;
flat in vec3 vDz;
layout(location = 0) out vec4 outSum;

void main() {
  precise vec3 x = vec3(uGridMin.xy + gl_FragCoord.xy * uGridCell.xy, uSliceZ);
  precise vec3 d = x - vPosR.xyz;
  float R = vPosR.w;
  // Inside the valid sphere by the CPU's test, without a square root (radiance_gather.comp.glsl).
  precise float d2 = d.x * d.x + (d.y * d.y + d.z * d.z);
  precise float R2 = R * R;
  if (!(d2 < R2)) discard;
  float dist = sqrt(d2);
  // A voxel centre on the sample itself: W is unbounded; a large finite weight keeps the sum a
  // weighted average dominated by this sample (the same clamp as the CPU twin in the tests).
  float W = R / max(dist, SL_SINGULAR_EPS * R);
#ifdef SL_OCCLUSION
  // Occlusion-aware weight (interpolateSamples' twin): exp(−σt·τ) of the segment from the
  // sample to the voxel, τ by the midpoint rule with steps of at most one density voxel.
  // Its steps as the CPU counts them: the length in its arithmetic (cpuLength, glm::length).
  vec3 p = vPosR.xyz;
  float len = cpuLength(d);
  int steps = stepCount(len, uDensityVoxel);
  float sum = 0.0;
  for (int m = 0; m < steps; ++m)
    sum += densityAtIndex((p + d * ((float(m) + 0.5) / float(steps))) * uDensityScale +
                          uDensityOffset);
  W *= exp(-uSigmaT * sum * (len / float(steps)));
#endif
  vec3 taylor = vS + d.x * vDx + d.y * vDy + d.z * vDz;
#ifdef SL_BOUNDED
  taylor = clamp(taylor, vec3(uTaylorBounds.x), vec3(uTaylorBounds.y));
#endif
  outSum = vec4(W * taylor, W);
}
