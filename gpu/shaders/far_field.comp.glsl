// A's far field (render.far_field; FarField of shading/transport.h, FarFieldCache of
// cpu/far_field.h): one invocation per vertex of the grid over the medium's box writes
// Σ_l w_l·A_l, w_l = farWeight (0 within R of a point light, 1 beyond 2R, 0 for the other
// lights), for the compute view march's farLookup. The isotropic phase only (the settings refuse
// the key otherwise), so A's terms do not depend on the direction to the viewer.
layout(local_size_x = 4, local_size_y = 4, local_size_z = 4) in;
// Names of its own (the march's are common.glsl's uFar*, under SL_FAR_FIELD).
#ifdef SL_FAR_UPDATE
// In place (gpu::ViewMarchGpu): the terms of the uChangedCount lights uChanged[] of the lights
// bound now, times uSign, added to each vertex's sum: once with the lights before (−1), once
// with the lights now (+1).
layout(std430, binding = BINDING_FAR_FIELD_OUT) buffer FarFieldOut { vec4 farOut[]; };
uniform int uChangedCount;
uniform int uChanged[32];
uniform float uSign;
#else
layout(std430, binding = BINDING_FAR_FIELD_OUT) writeonly buffer FarFieldOut { vec4 farOut[]; };
#endif
uniform float uBuildR;
uniform vec3 uBuildLo;
uniform vec3 uBuildCell;
uniform ivec3 uBuildDims;

void main() {
  ivec3 id = ivec3(gl_GlobalInvocationID);
  if (any(greaterThanEqual(id, uBuildDims))) return;
  vec3 x = uBuildLo + vec3(id) * uBuildCell;
  int v = (id.z * uBuildDims.y + id.y) * uBuildDims.x + id.x;
#ifdef SL_FAR_UPDATE
  vec3 a = farOut[v].xyz;
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
  farOut[v] = vec4(a, 0.0);
}
