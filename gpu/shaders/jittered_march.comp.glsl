// jittered-march, pass 1 (cpu/jittered_march.cpp, jitteredMarchLowRes): one invocation per
// low-resolution pixel, uSteps steps over the ray's piece inside the box at offsets
// (k + o)·Δt, S traced to every light at each sample. SL_OBJECTS: the ray ends at the surface
// pass's first surface, and S's visibility comes from the shadow maps (common.glsl). On a driver
// that caps loop iterations the lights may be split over dispatches (gpu::lightDispatches): this
// one traces lights uLightFirst, uLightFirst + uLightStride, … and, unless it is the first
// (uLightFirst 0), adds the L the ones before it stored.
layout(local_size_x = 8, local_size_y = 8) in;
layout(rgba32f, binding = BINDING_LOW_RES_IMAGE) uniform image2D uLow;
layout(r32f, binding = BINDING_LOW_RES_DEPTH_IMAGE) uniform writeonly image2D uLowDepth;
layout(std430, binding = BINDING_JITTER_TABLE) readonly buffer JitterTable { float jitterTable[]; };
uniform ivec2 uLowSize;
uniform int uDownsample;
uniform int uSteps;
uniform int uJitter;  // 0 none, 1 ign, 2 blue noise (Jitter order)
uniform int uTableSize;
uniform float uMinTransmittance;
uniform int uLightFirst;
uniform int uLightStride;

float jitterOffset(ivec2 p) {
  if (uJitter == 0) return 0.5;
  if (uJitter == 1) return interleavedGradientNoise(p);
  ivec2 q = ((p % uTableSize) + uTableSize) % uTableSize;
  return jitterTable[q.y * uTableSize + q.x];
}

void main() {
  ivec2 p = ivec2(gl_GlobalInvocationID.xy);
  if (any(greaterThanEqual(p, uLowSize))) return;
  vec3 dir = cameraRay((vec2(p) + 0.5) * float(uDownsample));
  vec3 L = vec3(0.0);
  float T = 1.0;
  // The first surface (the surface pass's nearest full-resolution pixel when downsampled).
  float hitT = surfaceDistance(ivec2((vec2(p) + 0.5) * float(uDownsample)));
  float t0, t1;
  bool inBox = intersectBox(uEye, dir, 0.0, kInf, t0, t1) && t1 > t0;
  float depth = !isinf(hitT) ? hitT : inBox ? t1 : kInf;
  if (inBox && uSigmaT > 0.0 && min(t1, hitT) > t0) {
    t1 = min(t1, hitT);
    // The CPU's steps as it rounds them (cpuDiv, `precise`; the ray from cameraRay).
    float dt = cpuDiv(t1 - t0, float(uSteps));
    float o = jitterOffset(p);
    precise vec3 u0 = (uEye + dir * (t0 + o * dt)) * uDensityScale + uDensityOffset;
    precise vec3 du = dir * dt * uDensityScale;
    for (int k = 0; k < uSteps && T > uMinTransmittance; ++k) {
      precise vec3 uk = u0 + float(k) * du;
      float D = densityAtIndex(uk);
      if (!(D > 0.0)) continue;
      float a = stepTransmittance(uSigmaT * D * dt);
      precise vec3 x = uEye + dir * (t0 + (float(k) + o) * dt);
      vec3 S = sourceRadiancePart(x, -dir, uLightFirst, max(uLightStride, 1));
      L += (T * uAlbedo * (1.0 - a)) * S;
      T *= a;
    }
  }
  if (uLightFirst > 0) L += imageLoad(uLow, p).rgb;
  imageStore(uLow, p, vec4(L, T));
  imageStore(uLowDepth, p, vec4(depth));
}
