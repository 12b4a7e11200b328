// The lamp model's k_l of every light (LampModel, shading/transport.h): σt·D(s_l), the density
// looked up at a point or spot light inside the medium's box, 0 for a directional light or one
// outside, into lights[li].lamp.x; and min_l m_l at the box's diagonal (LampModel::vBound's
// 1 / that) into lights[0].lamp.y. gpu::deviceLights runs it (one workgroup) where a lamp is
// inside the box, so the passes read k_l (common.glsl lampK) instead of eight density texels
// per light at every march step, sample and probe, and the radiance gather reads the minimum
// instead of evaluating every light's m_l at every voxel. After common.glsl (with
// SL_LAMP_MODEL), whose lights[] is read-only: the same buffer is written through its second
// name here.
layout(local_size_x = 64) in;
layout(std430, binding = BINDING_LIGHTS) buffer LightsOut { GpuLight lightsOut[]; };
uniform float uBoxDiagonal;
shared float sMin[64];

void main() {
  uint t = gl_LocalInvocationIndex;
  float m = 1.0;
  for (int li = int(t); li < uLightCount; li += 64) {
    GpuLight l = lights[li];
    vec3 p = l.positionType.xyz;
    bool inside = int(l.positionType.w) != 2 && all(greaterThanEqual(p, uBoxMin)) &&
                  all(lessThanEqual(p, uBoxMax));
    float k = inside ? uSigmaT * densityAtIndex(p * uDensityScale + uDensityOffset) : 0.0;
    lightsOut[li].lamp.x = k;
#ifdef SL_LAMP_MODEL
    m = min(m, lampModelAt(k, uBoxDiagonal));
#endif
  }
  sMin[t] = m;
  memoryBarrierShared();
  barrier();
  for (uint s = 32u; s > 0u; s >>= 1) {
    if (t < s) sMin[t] = min(sMin[t], sMin[t + s]);
    memoryBarrierShared();
    barrier();
  }
  if (t == 0u && uLightCount > 0) lightsOut[0].lamp.y = sMin[0];
}
